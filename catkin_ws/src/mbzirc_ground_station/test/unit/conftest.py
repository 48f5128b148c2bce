"""Lets the unit tests import the package (and mbzirc_arena, the arena model it draws) from the source trees
without a catkin build."""
import os
import sys

_SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..")
sys.path[:0] = [os.path.join(_SRC, pkg, "src") for pkg in ("mbzirc_ground_station", "mbzirc_arena")]
