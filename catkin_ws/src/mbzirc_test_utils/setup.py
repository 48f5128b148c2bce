"""Installs the pure-Python library of mbzirc_test_utils (catkin_python_setup)."""
from setuptools import setup

from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["mbzirc_test_utils"], package_dir={"": "src"}))
