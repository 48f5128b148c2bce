#!/usr/bin/env python3
"""Test fixture: static identity TF arena -> <each ~child_frames>, so TF lookups of fuzzed nodes succeed
and malformed values reach their logic instead of stopping at "frame does not exist"."""
import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped

if __name__ == "__main__":
    rospy.init_node("static_tf")
    frames = rospy.get_param("~child_frames", ["mbzirc2020_1/base_link"])
    out = []
    for f in frames:
        t = TransformStamped()
        t.header.frame_id = "arena"
        t.child_frame_id = f
        t.transform.rotation.w = 1.0
        out.append(t)
    tf2_ros.StaticTransformBroadcaster().sendTransform(out)
    rospy.spin()
