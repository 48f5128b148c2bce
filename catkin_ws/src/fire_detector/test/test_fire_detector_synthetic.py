#!/usr/bin/env python3
"""rostest: fire_detector fed by synthetic_thermal_publisher (one named scene per robot namespace).

Params: ~scene (a synthetic_thermal.NAMED_SCENES name), ~expect_fire (bool).
Checks the detections (type, ThermalImage fields, agent id, position error against the scene's known
fire), CheckFire, the debug topic, and that malformed inputs are survived.
"""
import math
import sys
import time
import unittest

import numpy as np
import rospy
import rostest
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList, ThermalImage
from mbzirc_comm_objs.srv import CheckFire
from mbzirc_test_utils.collector import Collector, agent_id
from sensor_msgs.msg import LaserScan, Temperature
from std_msgs.msg import Float64MultiArray

import synthetic_thermal as S  # test fixture in this folder

PKG = "fire_detector"


class TestFireDetectorSynthetic(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_fire_detector_synthetic")
        cls.scene_name = rospy.get_param("~scene")
        cls.expect_fire = bool(rospy.get_param("~expect_fire"))
        cls.scene = S.NAMED_SCENES[cls.scene_name]
        cls.ns_id = agent_id(rospy.get_namespace())
        cls.dets = Collector("sensed_objects", ObjectDetectionList)
        cls.debug = Collector("thermal_detection/debug", Temperature)
        rospy.wait_for_service("thermal_detection/fire_detected", timeout=30)
        cls.check = rospy.ServiceProxy("thermal_detection/fire_detected", CheckFire)
        rospy.wait_for_message("teraranger_evo_thermal/raw_temp_array", Float64MultiArray, timeout=30)

    def test_1_detections(self):
        if not self.expect_fire:
            time.sleep(4.0)  # > 50 frames at 14 Hz, far more than the 15-frame filter
            self.assertEqual(self.dets.count(), 0, f"{self.scene_name}: no fire expected")
            self.assertFalse(self.check().fire_detected)
            self.assertTrue(self.debug.count() > 10, "debug topic silent")
            return
        self.assertTrue(self.dets.wait(8, 20.0), f"{self.scene_name}: got {self.dets.count()} detections")
        self.assertTrue(self.check().fire_detected)
        truth = np.array(self.scene.source_arena())
        errors = []
        for lst in list(self.dets.msgs):
            self.assertEqual(lst.agent_id, self.ns_id)
            self.assertEqual(len(lst.objects), 1)
            o = lst.objects[0]
            self.assertEqual(o.type, ObjectDetection.TYPE_FIRE)
            self.assertEqual(o.color, ObjectDetection.COLOR_FIRE)
            self.assertEqual(o.header.frame_id, "arena")
            im = o.image_detection
            self.assertEqual((im.img_width, im.img_height), (32, 32))
            want_dir = ThermalImage.CAMERA_DIRECTION_FORWARD if self.scene.direction == 1 else ThermalImage.CAMERA_DIRECTION_DOWNWARD
            self.assertEqual(im.camera_direction, want_dir)
            # the original's u, v: offsets from the image centre (px); its fixed 3.5 px size
            self.assertTrue(abs(im.u) <= 16 and abs(im.v) <= 16 and im.width == im.height == 3.5)
            self.assertAlmostEqual(im.depth, self.scene.distance, delta=0.4)
            self.assertAlmostEqual(o.pose.covariance[0], 1.5 ** 2)      # covariance_x is a std: its variance
            p = o.pose.pose.position
            errors.append(float(np.linalg.norm(np.array([p.x, p.y, p.z]) - truth)))
        self.assertLess(float(np.median(errors)), 0.35, f"position errors {errors}")
        self.assertTrue(self.debug.count() > 10, "debug topic silent")

    def test_2_survives_bad_input(self):
        temp_pub = rospy.Publisher("teraranger_evo_thermal/raw_temp_array", Float64MultiArray, queue_size=10)
        scan_pub = rospy.Publisher("scan", LaserScan, queue_size=10)
        time.sleep(1.0)
        for _ in range(5):
            temp_pub.publish(Float64MultiArray(data=[40.0] * 100))
            temp_pub.publish(Float64MultiArray(data=[float("nan")] * 1024))
            scan_pub.publish(LaserScan(angle_min=-math.pi, angle_increment=0.0, ranges=[float("nan")] * 720))
            time.sleep(0.05)
        before = self.dets.count()
        self.check()  # still answering
        if self.expect_fire:
            self.assertTrue(self.dets.wait(before + 3, 15.0), "no detections after bad input")
        else:
            time.sleep(2.0)
            self.assertEqual(self.dets.count(), 0)


if __name__ == "__main__":
    rostest.rosrun(PKG, "fire_detector_synthetic_" + sys.argv[0].rsplit("/", 1)[-1], TestFireDetectorSynthetic)
