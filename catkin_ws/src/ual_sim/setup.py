"""Installs the pure-Python ual_sim library (world model, sensors, effects) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["ual_sim"], package_dir={"": "src"}))
