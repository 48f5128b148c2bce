"""Installs the mbzirc_arena Python library (src/mbzirc_arena) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['mbzirc_arena'], package_dir={'': 'src'}))
