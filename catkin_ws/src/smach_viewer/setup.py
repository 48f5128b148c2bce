"""Installs the smach_viewer Python library and its page (catkin_python_setup)."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["smach_viewer"], package_dir={"": "src"},
                                 package_data={"smach_viewer": ["static/index.html"]}))
