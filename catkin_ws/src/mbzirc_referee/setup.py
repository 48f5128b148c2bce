"""Installs the mbzirc_referee Python library (src/mbzirc_referee) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['mbzirc_referee'], package_dir={'': 'src'}))
