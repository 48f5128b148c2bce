#!/usr/bin/env python3
"""rostest: circle_detector on an RGB-D rosbag recorded from ual_sim in front of an active facade holder.

Param ~bag: a file of test/data/bags.yaml (namespace, true hole position in the arena, UAV pose).
Checks that the three circles are found and that the chosen middle hole is the real one.
"""
import math
import time
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import PointStamped
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
from mbzirc_test_utils.bag_replay import bag_case, play_bag_when_subscribed, stop, wait_for_replay
from mbzirc_test_utils.collector import Collector
from sensor_msgs.msg import Image

PKG = "circle_detector"
CAM_OFFSET_X = 0.15  # ual_sim: base_link -> camera_color_optical_frame, 0.15 m ahead
MAX_HOLE_ERROR_M = 0.15


def hole_in_camera(hole, uav_xyz_yaw):
    """Optical-frame position (x right, y down, z forward) of an arena point seen from a level UAV."""
    x, y, z, yaw = uav_xyz_yaw
    dx, dy, dz = hole[0] - x, hole[1] - y, hole[2] - z
    bx = math.cos(yaw) * dx + math.sin(yaw) * dy - CAM_OFFSET_X
    by = -math.sin(yaw) * dx + math.cos(yaw) * dy
    return np.array([-by, -dz, bx])


class TestCircleDetectorBag(unittest.TestCase):
    def test_replay(self):
        rospy.init_node("test_circle_detector_bag")
        path, bag, truth = bag_case(PKG)
        want = hole_in_camera(truth["hole_arena"], truth["uav_xyz_yaw"])
        detections = Collector("sensed_objects", ObjectDetectionList)
        middle_holes = Collector("circle_detection/middle_hole", PointStamped)
        colour = Collector("camera/color/image_rect_color", Image, keep=False)
        player = play_bag_when_subscribed(path, "/circle_detector", "camera/aligned_depth_to_color/image_raw")
        self.addCleanup(stop, player)
        self.assertTrue(wait_for_replay(colour), "the bag never played")
        time.sleep(1.0)
        dets, holes, n_frames = list(detections.msgs), list(middle_holes.msgs), colour.count()
        rospy.loginfo(f"{bag}: {n_frames} frames, {len(dets)} detection lists, {len(holes)} middle holes")
        self.assertGreaterEqual(len(dets), max(1, n_frames // 2))
        full = [d for d in dets if len(d.objects) == 3]
        self.assertGreaterEqual(len(full), len(dets) * 0.8, "three circles expected in most frames")
        for d in dets:
            self.assertTrue(all(o.type == ObjectDetection.TYPE_HOLE for o in d.objects))
        self.assertGreaterEqual(len(holes), len(full))
        errors = [float(np.linalg.norm(np.array([h.point.x, h.point.y, h.point.z]) - want)) for h in holes]
        rospy.loginfo(f"{bag}: hole error median {np.median(errors):.3f} max {max(errors):.3f} m (want {want})")
        self.assertLess(max(errors), MAX_HOLE_ERROR_M)


if __name__ == "__main__":
    rostest.rosrun(PKG, "circle_detector_bag", TestCircleDetectorBag)
