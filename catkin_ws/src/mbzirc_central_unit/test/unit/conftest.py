"""Lets the unit tests import the package (and mbzirc_agents, whose geometry it uses) from src/ without a
catkin build."""
import os
import sys

HERE = os.path.dirname(__file__)
sys.path[:0] = [os.path.join(HERE, "..", "..", "src"), os.path.join(HERE, "..", "..", "..", "mbzirc_agents", "src")]
