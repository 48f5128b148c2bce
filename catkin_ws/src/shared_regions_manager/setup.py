"""Installs the shared_regions_manager Python library (src/shared_regions_manager) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['shared_regions_manager'], package_dir={'': 'src'}))
