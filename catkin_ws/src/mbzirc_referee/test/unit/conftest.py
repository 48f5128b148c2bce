"""Lets the unit tests import mbzirc_referee (and the workspace libraries it uses) from the source trees without a
catkin build."""
import os
import sys

_SRC = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..')
sys.path[:0] = [os.path.join(_SRC, pkg, 'src') for pkg in ('mbzirc_referee', 'mbzirc_arena', 'mbzirc_ros_utils')]
