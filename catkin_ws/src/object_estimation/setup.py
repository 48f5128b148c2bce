"""Installs the object_estimation Python library (src/object_estimation) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['object_estimation'], package_dir={'': 'src'}))
