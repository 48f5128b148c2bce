"""Installs the smach_ros Python library (catkin_python_setup)."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["smach_ros"], package_dir={"": "src"}))
