"""Lets the unit tests import mbzirc_agents (and the workspace's smach and mbzirc_arena) from the source tree without a
catkin build."""
import os
import sys

_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(_HERE, '..', '..', 'src'))
sys.path.insert(0, os.path.join(_HERE, '..', '..', '..', 'mbzirc_arena', 'src'))
sys.path.insert(0, _HERE)
try:
    import smach  # noqa: F401
except ImportError:
    sys.path.append(os.path.join(_HERE, '..', '..', '..', 'smach', 'src'))
