"""Installs the pure-Python library of circle_detector (catkin_python_setup)."""
from setuptools import setup

from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["circle_detector"], package_dir={"": "src"}))
