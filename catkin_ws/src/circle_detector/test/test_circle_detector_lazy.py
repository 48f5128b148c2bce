#!/usr/bin/env python3
"""rostest: circle_detector ~lazy processes camera images only while middle_hole has a subscriber.

Checks that the node does not even subscribe to the camera (so a simulator renders nothing for it)
while only sensed_objects is listened to, starts when a client subscribes to middle_hole, and stops
again when that client leaves.
"""
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import PointStamped
from mbzirc_comm_objs.msg import ObjectDetectionList
from sensor_msgs.msg import Image

COLOR = "camera/color/image_rect_color"


class Counter:
    """Counts messages of a subscription."""

    def __init__(self, topic, cls):
        self.n, self.lock = 0, threading.Lock()
        self.sub = rospy.Subscriber(topic, cls, self.cb, queue_size=50)

    def cb(self, _msg):
        with self.lock:
            self.n += 1

    def count(self):
        with self.lock:
            return self.n


def wait_until(pred, timeout):
    end = time.time() + timeout
    while time.time() < end and not rospy.is_shutdown():
        if pred():
            return True
        time.sleep(0.05)
    return pred()


class TestLazyCircleDetector(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_circle_detector_lazy")
        cls.color_probe = rospy.Publisher(COLOR, Image, queue_size=1)   # only to read its subscriber count

    def camera_subscribed(self):
        """Whether the detector has a connection to the colour image topic (our probe counts them)."""
        state = rospy.get_master().getSystemState()[2][1]
        subs = [names for topic, names in state if topic == rospy.resolve_name(COLOR)]
        return bool(subs) and any(n.endswith("/circle_detector") for n in subs[0])

    def test_lazy_on_and_off(self):
        dets = Counter("sensed_objects", ObjectDetectionList)
        # the publisher and the detector come up; with only sensed_objects listened to, nothing happens
        self.assertTrue(wait_until(lambda: dets.sub.get_num_connections() > 0, 30.0), "detector not up")
        time.sleep(2.0)
        self.assertFalse(self.camera_subscribed(), "lazy detector subscribed to the camera without demand")
        self.assertEqual(dets.count(), 0, "lazy detector published detections without demand")

        holes = Counter("circle_detection/middle_hole", PointStamped)
        self.assertTrue(wait_until(self.camera_subscribed, 10.0), "demand did not subscribe the camera")
        self.assertTrue(wait_until(lambda: holes.count() >= 3, 30.0),
                        f"only {holes.count()} middle holes after the demand")
        self.assertGreater(dets.count(), 0)

        holes.sub.unregister()
        self.assertTrue(wait_until(lambda: not self.camera_subscribed(), 10.0),
                        "detector kept the camera after the demand left")
        time.sleep(1.0)
        before = dets.count()
        time.sleep(2.0)
        self.assertEqual(dets.count(), before, "detections kept coming without demand")


if __name__ == "__main__":
    rostest.rosrun("circle_detector", "lazy", TestLazyCircleDetector)
