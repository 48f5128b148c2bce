"""Lets the unit tests import shared_regions_manager (and the workspace libraries it uses) from the source trees without a
catkin build."""
import os
import sys

_SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..')
sys.path[:0] = [os.path.join(_SRC, pkg, 'src') for pkg in ('mbzirc_ros_utils', 'shared_regions_manager', 'mbzirc_arena')]
