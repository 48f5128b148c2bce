"""Lets the unit tests import the package (and mbzirc_arena, whose arena it plans in) from src/ without a
catkin build."""
import os
import sys

HERE = os.path.dirname(__file__)
sys.path[:0] = [os.path.join(HERE, "..", "..", "src"), os.path.join(HERE, "..", "..", "..", "mbzirc_arena", "src")]
