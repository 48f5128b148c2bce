"""Small ROS helpers shared by every node (no dependency on other project packages)."""
