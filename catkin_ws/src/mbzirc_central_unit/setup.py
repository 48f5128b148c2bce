"""Installs the pure-Python library of mbzirc_central_unit (the strategy core)."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["mbzirc_central_unit"], package_dir={"": "src"}))
