"""Thermal fire detection for the MBZIRC 2020 Challenge 3 UAVs (pure logic + a thin ROS node)."""
