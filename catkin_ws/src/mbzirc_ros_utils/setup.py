"""Installs the mbzirc_ros_utils Python library (src/mbzirc_ros_utils) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['mbzirc_ros_utils'], package_dir={'': 'src'}))
