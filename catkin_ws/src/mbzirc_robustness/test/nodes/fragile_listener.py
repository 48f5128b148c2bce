#!/usr/bin/env python3
"""Test fixture: a node that exits on a NaN (the fuzzer must report it dead, with the input)."""
import math
import os

import rospy
from geometry_msgs.msg import PoseStamped


def on_pose(msg: PoseStamped) -> None:
    if math.isnan(msg.pose.position.x):
        os._exit(3)  # what an unguarded crash in a C extension or a bad sys.exit in a callback looks like


if __name__ == "__main__":
    rospy.init_node("fragile_listener")
    rospy.Subscriber("pose", PoseStamped, on_pose, queue_size=5)
    rospy.spin()
