"""Installs the pure-Python hector_mapping library (src/hector_mapping) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["hector_mapping"], package_dir={"": "src"}))
