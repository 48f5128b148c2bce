#!/usr/bin/env python3
"""rostest: circle_detector on synthetic RGB-D facades.

~mode "publisher": a synthetic_rgbd_publisher runs in this namespace (~scene); checks the TYPE_HOLE
detections and the chosen middle hole against the scene, then survives malformed images.
~mode "self": nothing else publishes; the test sends images before any camera_info (no output, node
alive), then camera_info and images (detections appear).
"""
import time
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import PointStamped
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
from mbzirc_test_utils.collector import Collector, agent_id
from sensor_msgs.msg import CameraInfo, Image

import synthetic_rgbd as S  # test fixture in this folder

PKG = "circle_detector"


def image(arr, encoding, frame_id, stamp):
    ch = 1 if arr.ndim == 2 else arr.shape[2]
    msg = Image(height=arr.shape[0], width=arr.shape[1], encoding=encoding, is_bigendian=0,
                step=arr.shape[1] * ch * arr.itemsize, data=arr.tobytes())
    msg.header.stamp, msg.header.frame_id = stamp, frame_id
    return msg


class TestCircleDetectorSynthetic(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_circle_detector_synthetic")
        cls.mode = rospy.get_param("~mode", "publisher")
        cls.scene_name = rospy.get_param("~scene", "facade_holder")
        cls.scene = S.NAMED_SCENES[cls.scene_name]
        cls.ns = rospy.get_namespace().strip("/")
        cls.frame = f"{cls.ns}/camera_color_optical_frame"
        cls.dets = Collector("sensed_objects", ObjectDetectionList)
        cls.holes = Collector("circle_detection/middle_hole", PointStamped)
        cls.color_pub = rospy.Publisher("camera/color/image_rect_color", Image, queue_size=5)
        cls.depth_pub = rospy.Publisher("camera/aligned_depth_to_color/image_raw", Image, queue_size=5)
        cls.info_pub = rospy.Publisher("camera/color/camera_info", CameraInfo, queue_size=5)

    def send(self, colour, depth, c_enc="bgr8", d_enc="16UC1"):
        stamp = rospy.Time.now()
        self.color_pub.publish(image(colour, c_enc, self.frame, stamp))
        self.depth_pub.publish(image(depth, d_enc, self.frame, stamp))

    def test_detections(self):
        if self.mode == "self":
            return self.self_fed()
        self.assertTrue(self.dets.wait(5, 40.0), f"only {self.dets.count()} sensed_objects")
        if self.scene.radius <= 0:
            time.sleep(1.0)
            self.assertTrue(all(len(m.objects) == 0 for m in self.dets.msgs))
            self.assertEqual(self.holes.count(), 0)
            return
        self.assertTrue(self.holes.wait(5, 20.0))
        for lst in list(self.dets.msgs):
            self.assertEqual(lst.agent_id, agent_id(self.ns))
            self.assertEqual(len(lst.objects), 3)
            for o in lst.objects:
                self.assertEqual(o.type, ObjectDetection.TYPE_HOLE)
                self.assertEqual(o.header.frame_id, self.frame)
                self.assertAlmostEqual(o.scale.x, self.scene.radius, delta=0.04)
        for h in list(self.holes.msgs):
            err = np.linalg.norm(np.array([h.point.x, h.point.y, h.point.z]) - np.array(self.scene.hole_cam))
            self.assertLess(err, 0.06)
        # malformed input: sizes differ, unknown encoding, truncated data; the node keeps going
        before = self.dets.count()
        for _ in range(3):
            self.send(np.zeros((480, 640, 3), np.uint8), np.zeros((240, 320), np.uint16))
            self.send(np.zeros((480, 640, 2), np.uint8), np.zeros((480, 640), np.uint16), c_enc="yuv422")
            bad = image(np.zeros((480, 640), np.uint16), "16UC1", self.frame, rospy.Time.now())
            bad.data = bad.data[:1000]
            self.color_pub.publish(image(np.zeros((480, 640, 3), np.uint8), "bgr8", self.frame, bad.header.stamp))
            self.depth_pub.publish(bad)
            time.sleep(0.1)
        self.assertTrue(self.dets.wait(before + 5, 20.0), "no detections after bad input")

    def self_fed(self):
        rng = np.random.default_rng(4)
        colour, depth = S.render(self.scene, rng)
        time.sleep(2.0)  # let the detector connect
        for _ in range(10):
            self.send(colour, depth)
            time.sleep(0.1)
        time.sleep(1.0)
        self.assertEqual(self.dets.count(), 0, "no camera_info yet: nothing may be published")
        K = S.DEFAULT_K
        info = CameraInfo(height=K.height, width=K.width, K=[K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1])
        info.header.frame_id = self.frame
        end = time.time() + 30.0
        while time.time() < end and self.dets.count() < 3:
            self.info_pub.publish(info)
            self.send(colour, depth)
            time.sleep(0.2)
        self.assertTrue(self.dets.wait(3, 5.0), "camera_info arrived, still no detections")
        self.assertEqual(len(self.dets.msgs[-1].objects), 3)


if __name__ == "__main__":
    rostest.rosrun(PKG, "circle_detector_synthetic", TestCircleDetectorSynthetic)
