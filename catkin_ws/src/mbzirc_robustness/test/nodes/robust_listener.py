#!/usr/bin/env python3
"""Test fixture: a node that validates every input and logs a clear throttled error (must survive)."""
import math

import rospy
from sensor_msgs.msg import Image
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger, TriggerResponse


def on_array(msg: Float64MultiArray) -> None:
    if len(msg.data) != 1024:
        rospy.logerr_throttle(1.0, "robust_listener: raw_temp_array has %d values, expected 1024" % len(msg.data))
        return
    if not all(math.isfinite(v) for v in msg.data):
        rospy.logerr_throttle(1.0, "robust_listener: raw_temp_array has NaN/inf values")


def on_image(msg: Image) -> None:
    if msg.encoding != "rgb8" or msg.height * msg.step != len(msg.data) or msg.height == 0:
        rospy.logerr_throttle(1.0, "robust_listener: bad image %dx%d %r (%d bytes)"
                              % (msg.width, msg.height, msg.encoding, len(msg.data)))


def on_trigger(_req) -> TriggerResponse:
    return TriggerResponse(success=False, message="robust_listener: nothing to trigger")


if __name__ == "__main__":
    rospy.init_node("robust_listener")
    rospy.Subscriber("raw_temp_array", Float64MultiArray, on_array, queue_size=5)
    rospy.Subscriber("rgb_image", Image, on_image, queue_size=5)
    rospy.Service("trigger", Trigger, on_trigger)
    rospy.spin()
