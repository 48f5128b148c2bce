#!/usr/bin/env python3
"""rostest: fire_detector on a rosbag recorded from ual_sim, replayed with `rosbag play --clock`.

Param ~bag: a file of test/data/bags.yaml (which holds the robot namespace, the camera and the true fire
position from /sim/fires, or null). Checks the number of detections and their position error, or that
nothing is detected, and the CheckFire answer after the replay.
"""
import math
import time
import unittest

import numpy as np
import rospy
import rostest
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
from mbzirc_comm_objs.srv import CheckFire
from mbzirc_test_utils.bag_replay import bag_case, play_bag_when_subscribed, stop, wait_for_replay
from mbzirc_test_utils.collector import Collector, agent_id
from std_msgs.msg import Float64MultiArray

PKG = "fire_detector"
MIN_DETECTIONS = 20       # the bags hold 65-75 thermal frames; the filter needs 16
MAX_MEDIAN_ERROR_M = 0.3
MAX_ERROR_M = 1.0


class TestFireDetectorBag(unittest.TestCase):
    def test_replay(self):
        rospy.init_node("test_fire_detector_bag")
        path, bag, truth = bag_case(PKG)
        detections = Collector("sensed_objects", ObjectDetectionList)
        thermal = Collector("teraranger_evo_thermal/raw_temp_array", Float64MultiArray, keep=False)
        rospy.wait_for_service("thermal_detection/fire_detected", timeout=60)
        check = rospy.ServiceProxy("thermal_detection/fire_detected", CheckFire)
        player = play_bag_when_subscribed(path, "/fire_detector", "teraranger_evo_thermal/raw_temp_array")
        self.addCleanup(stop, player)
        self.assertTrue(wait_for_replay(thermal), "the bag never played")
        time.sleep(0.5)
        dets, n_frames = list(detections.msgs), thermal.count()
        rospy.loginfo(f"{bag}: {n_frames} thermal frames, {len(dets)} detections")
        if truth["fire"] is None:
            self.assertEqual(len(dets), 0, f"{bag}: {len(dets)} false detections")
            self.assertFalse(check().fire_detected)
            return
        self.assertGreaterEqual(len(dets), MIN_DETECTIONS, f"{bag}: {len(dets)} detections of {n_frames} frames")
        errors = []
        for lst in dets:
            self.assertEqual(lst.agent_id, agent_id(truth["ns"]))
            o = lst.objects[0]
            self.assertEqual(o.type, ObjectDetection.TYPE_FIRE)
            p = o.pose.pose.position
            errors.append(math.dist((p.x, p.y, p.z), truth["fire"]))
        rospy.loginfo(f"{bag}: position error median {np.median(errors):.3f} max {max(errors):.3f} m")
        self.assertLess(float(np.median(errors)), MAX_MEDIAN_ERROR_M)
        self.assertLess(max(errors), MAX_ERROR_M)
        self.assertTrue(check().fire_detected)


if __name__ == "__main__":
    rostest.rosrun(PKG, "fire_detector_bag", TestFireDetectorBag)
