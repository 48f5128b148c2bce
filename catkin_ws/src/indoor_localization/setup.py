"""Installs the indoor_localization Python library (src/indoor_localization) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['indoor_localization'], package_dir={'': 'src'}))
