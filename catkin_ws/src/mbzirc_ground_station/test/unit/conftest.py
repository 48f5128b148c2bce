"""Lets the unit tests import the package from src/ without a catkin build."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "src"))
