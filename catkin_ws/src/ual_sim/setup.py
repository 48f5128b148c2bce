"""Installs the pure-Python ual_sim library (world model, sensors, effects) and its default world file."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["ual_sim"], package_dir={"": "src"},
                                 package_data={"ual_sim": ["worlds/*.yaml"]}))
