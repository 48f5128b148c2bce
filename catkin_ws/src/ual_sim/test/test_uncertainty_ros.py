#!/usr/bin/env python3
"""rostest (uncertainty:=realistic): three UAVs hover outdoors; over 120 sim-s their reported pose
(`ual/pose`) stays on the commanded waypoint while the true one (`/sim/robots`) is off it by the GNSS bias,
which wanders: the error has the configured size (0.5 m per horizontal axis, 0.4 m vertical) and changes
over the correlation time (30 s)."""
import math
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from geometry_msgs.msg import PoseArray, PoseStamped
from rosgraph_msgs.msg import Clock
from uav_abstraction_layer.srv import GoToWaypoint, TakeOff

UAVS = (1, 2, 3)
WAYPOINTS = {1: (-4.0, 2.0, 4.0), 2: (0.0, -4.0, 4.0), 3: (4.0, 2.0, 4.0)}   # open ground, far from the building


class Poses:
    """Latest reported pose of each UAV and, at each /sim/robots message, (sim time, reported - true)."""

    def __init__(self):
        self.lock = threading.Lock()
        self.reported = {}
        self.errors = {i: [] for i in UAVS}
        self.ids = None
        for i in UAVS:
            rospy.Subscriber(f"/mbzirc2020_{i}/ual/pose", PoseStamped, self.on_pose, callback_args=i, queue_size=1)
        rospy.Subscriber("/sim/robots", PoseArray, self.on_truth, queue_size=5)

    def on_pose(self, m, i):
        p = m.pose.position
        with self.lock:
            self.reported[i] = np.array([p.x, p.y, p.z])

    def on_truth(self, m):
        ids = self.ids or rospy.get_param("/sim/robot_ids")
        self.ids = ids
        t = m.header.stamp.to_sec()
        with self.lock:
            for rid, pose in zip(ids, m.poses):
                if rid in self.reported:
                    p = pose.position
                    self.errors[rid].append((t, self.reported[rid] - np.array([p.x, p.y, p.z])))


def wait_sim(seconds):
    end = rospy.get_time() + seconds
    while rospy.get_time() < end and not rospy.is_shutdown():
        time.sleep(0.05)


class TestUncertainty(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_uncertainty")
        rospy.wait_for_message("/clock", Clock, timeout=60)
        cls.poses = Poses()
        for i in UAVS:
            rospy.wait_for_service(f"/mbzirc2020_{i}/ual/take_off", timeout=60)
            rospy.ServiceProxy(f"/mbzirc2020_{i}/ual/take_off", TakeOff)(3.0, True)
        for i in UAVS:
            wp = PoseStamped()
            wp.header.frame_id = "arena"
            wp.pose.position.x, wp.pose.position.y, wp.pose.position.z = WAYPOINTS[i]
            wp.pose.orientation.w = 1.0
            rospy.ServiceProxy(f"/mbzirc2020_{i}/ual/go_to_waypoint", GoToWaypoint)(wp, True)
        wait_sim(10.0)                                   # settled on the waypoints
        with cls.poses.lock:
            for i in UAVS:
                cls.poses.errors[i].clear()
        wait_sim(120.0)

    def test_reported_pose_stays_on_the_command(self):
        with self.poses.lock:
            rep = dict(self.poses.reported)
        for i in UAVS:
            err = np.linalg.norm(rep[i] - np.array(WAYPOINTS[i]))
            self.assertLess(err, 0.35, f"UAV {i} believes it is {err:.2f} m from its waypoint")

    def test_error_has_the_configured_size_and_wanders(self):
        with self.poses.lock:
            series = {i: list(v) for i, v in self.poses.errors.items()}
        allerr = []
        for i in UAVS:
            self.assertGreater(len(series[i]), 100, f"UAV {i}: too few samples of /sim/robots")
            t = np.array([s[0] for s in series[i]])
            e = np.array([s[1] for s in series[i]])
            allerr.append(e)
            self.assertGreater(t[-1] - t[0], 100.0)
            # wanders: the error 60 s apart differs (a constant offset would not)
            later = np.searchsorted(t, t[0] + 60.0)
            drift = np.linalg.norm(e[later:] - e[:len(e) - later], axis=1)
            self.assertGreater(drift.mean(), 0.05, f"UAV {i}: the GNSS error does not wander")
            # slowly: from one 2 Hz sample to the next it moves by centimetres, not by its whole size
            self.assertLess(np.median(np.linalg.norm(np.diff(e, axis=0), axis=1)), 0.25)
        e = np.vstack(allerr)
        rms_xy = math.sqrt(float((e[:, :2] ** 2).sum(axis=1).mean()))
        # 3 UAVs x 120 s is ~12 correlation times: the horizontal RMS is within a factor ~2.5 of 0.71 m
        self.assertGreater(rms_xy, 0.25, f"horizontal GNSS error RMS {rms_xy:.2f} m, expected ~0.71")
        self.assertLess(rms_xy, 1.8, f"horizontal GNSS error RMS {rms_xy:.2f} m, expected ~0.71")
        self.assertLess(float(np.abs(e[:, 2]).max()), 2.5)


if __name__ == "__main__":
    rostest.rosrun("ual_sim", "uncertainty", TestUncertainty)
