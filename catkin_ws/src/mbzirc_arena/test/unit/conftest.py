"""Lets the unit tests import mbzirc_arena from the source tree without a catkin build."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'src'))
