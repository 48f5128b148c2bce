#!/usr/bin/env python3
"""rostest: fire_detector on a rosbag recorded from ual_sim, replayed with `rosbag play --clock`.

Param ~bag: a file of test/data/bags.yaml (which holds the robot namespace, the camera and the true fire
position from /sim/fires, or null). Checks the number of detections and their position error, or that
nothing is detected, and the CheckFire answer after the replay.
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
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
from mbzirc_comm_objs.srv import CheckFire
from std_msgs.msg import Float64MultiArray

PKG = "fire_detector"
MIN_DETECTIONS = 20       # the bags hold 65-75 thermal frames; the filter needs 16
MAX_MEDIAN_ERROR_M = 0.3
MAX_ERROR_M = 1.0


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


class TestFireDetectorBag(unittest.TestCase):
    def test_replay(self):
        rospy.init_node("test_fire_detector_bag")
        bag = rospy.get_param("~bag")
        data = os.path.join(rospkg.RosPack().get_path(PKG), "test", "data")
        with open(os.path.join(data, "bags.yaml")) as f:
            truth = yaml.safe_load(f)[bag]
        lock = threading.Lock()
        dets, frames = [], []
        rospy.Subscriber("sensed_objects", ObjectDetectionList, lambda m: (lock.acquire(), dets.append(m), lock.release()))
        rospy.Subscriber("teraranger_evo_thermal/raw_temp_array", Float64MultiArray,
                         lambda m: (lock.acquire(), frames.append(time.time()), lock.release()))
        rospy.wait_for_service("thermal_detection/fire_detected", timeout=60)
        check = rospy.ServiceProxy("thermal_detection/fire_detected", CheckFire)
        # wait for the replay to start and to end (no thermal frame for 3 s)
        player = play_bag_when_subscribed(os.path.join(data, bag), "/fire_detector", "teraranger_evo_thermal/raw_temp_array")
        self.addCleanup(stop, player)
        end = time.time() + 90
        while time.time() < end and not frames:
            time.sleep(0.1)
        self.assertTrue(frames, "the bag never played")
        while time.time() < end and time.time() - frames[-1] < 3.0:
            time.sleep(0.1)
        time.sleep(0.5)
        rospy.loginfo(f"{bag}: {len(frames)} thermal frames, {len(dets)} detections")
        if truth["fire"] is None:
            self.assertEqual(len(dets), 0, f"{bag}: {len(dets)} false detections")
            self.assertFalse(check().fire_detected)
            return
        self.assertGreaterEqual(len(dets), MIN_DETECTIONS, f"{bag}: {len(dets)} detections of {len(frames)} frames")
        errors = []
        for lst in dets:
            self.assertEqual(lst.agent_id, truth["ns"].rsplit("_", 1)[-1])
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
