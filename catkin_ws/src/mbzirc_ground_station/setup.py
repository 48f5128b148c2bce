"""Installs the mbzirc_ground_station Python library and its page (catkin_python_setup)."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["mbzirc_ground_station"], package_dir={"": "src"},
                                 package_data={"mbzirc_ground_station": ["static/index.html"]}))
