"""Installs the mbzirc_agents Python library (src/mbzirc_agents) for catkin."""
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=['mbzirc_agents', 'mbzirc_agents.tasks'],
                                 package_dir={'': 'src'}))
