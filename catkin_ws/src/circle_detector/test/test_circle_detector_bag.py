#!/usr/bin/env python3
"""rostest: circle_detector on an RGB-D rosbag recorded from ual_sim in front of an active facade holder.

Param ~bag: a file of test/data/bags.yaml (namespace, true hole position in the arena, UAV pose).
Checks that the three circles are found and that the chosen middle hole is the real one.
"""
import math
import os
import threading
import time
import unittest

import numpy as np
import rospkg
import rospy
import rostest
import yaml
from geometry_msgs.msg import PointStamped
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
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


def play_bag_when_subscribed(path, node_suffix, topic_suffix, timeout=90.0):
    """Starts `rosbag play --clock` once a node named *node_suffix subscribes to *topic_suffix.

    Playing only then (instead of after a fixed delay) keeps the test independent of how slowly nodes
    start on a loaded machine. Returns the player process.
    """
    import subprocess

    import rosgraph

    master = rosgraph.Master("/test_bag_player")
    end = time.time() + timeout
    while time.time() < end:
        _, subs, _ = master.getSystemState()
        if any(t.endswith(topic_suffix) and any(n.endswith(node_suffix) for n in nodes) for t, nodes in subs):
            break
        time.sleep(0.2)
    time.sleep(0.5)
    return subprocess.Popen(["rosbag", "play", "--clock", "-q", path])


def stop(player):
    """Ends the player if it is still running (it may linger after the last message)."""
    import subprocess

    try:
        player.wait(5)
    except subprocess.TimeoutExpired:
        player.terminate()
        player.wait(10)


class TestCircleDetectorBag(unittest.TestCase):
    def test_replay(self):
        rospy.init_node("test_circle_detector_bag")
        bag = rospy.get_param("~bag")
        data = os.path.join(rospkg.RosPack().get_path(PKG), "test", "data")
        with open(os.path.join(data, "bags.yaml")) as f:
            truth = yaml.safe_load(f)[bag]
        want = hole_in_camera(truth["hole_arena"], truth["uav_xyz_yaw"])
        lock = threading.Lock()
        dets, holes, frames = [], [], []

        def keep(store):
            return lambda m: (lock.acquire(), store.append(m), lock.release())

        rospy.Subscriber("sensed_objects", ObjectDetectionList, keep(dets))
        rospy.Subscriber("circle_detection/middle_hole", PointStamped, keep(holes))
        rospy.Subscriber("camera/color/image_rect_color", Image, lambda m: frames.append(time.time()))
        player = play_bag_when_subscribed(os.path.join(data, bag), "/circle_detector", "camera/aligned_depth_to_color/image_raw")
        self.addCleanup(stop, player)
        end = time.time() + 90
        while time.time() < end and not frames:
            time.sleep(0.1)
        self.assertTrue(frames, "the bag never played")
        while time.time() < end and time.time() - frames[-1] < 3.0:
            time.sleep(0.1)
        time.sleep(1.0)
        rospy.loginfo(f"{bag}: {len(frames)} frames, {len(dets)} detection lists, {len(holes)} middle holes")
        self.assertGreaterEqual(len(dets), max(1, len(frames) // 2))
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
