#!/usr/bin/env python3
"""rostest: hector_mapping on the replayed fast-turning flight, against the simulator's ground truth.

Checks the trajectory (every slam_out_pose against the true pose of the same stamp, the map frame being
the true pose at the first processed scan), the final pose, TF map -> base_link, the map's walls against the world's wall
surfaces, the pose covariance, and then the pause_mapping / reset_map services.
"""
import json
import math
import sys
import time
import unittest

import numpy as np
import rosbag
import rosgraph
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from nav_msgs.srv import GetMap
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from std_srvs.srv import SetBool, Trigger
from tf2_msgs.msg import TFMessage

from indoor import map_wall_check  # test fixture in this folder

NS = "mbzirc2020_1"


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


class ReplayTest(unittest.TestCase):
    """One replay of the recording; the checks share it."""

    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_hector_replay")
        with open(rospy.get_param("~meta")) as f:
            cls.meta = json.load(f)
        cls.est = {}
        cls.truth = {}
        cls.cov = []
        rospy.Subscriber("slam_out_pose", PoseStamped, cls._on_pose, queue_size=1000)
        rospy.Subscriber("poseupdate", PoseWithCovarianceStamped,
                         lambda m: cls.cov.append(np.array(m.pose.covariance).reshape(6, 6)), queue_size=1000)
        cls.tf_buffer = tf2_ros.Buffer()
        cls.tf_listener = tf2_ros.TransformListener(cls.tf_buffer)
        cls.replay(rospy.get_param("~bag"))
        cls.tf_final = None
        try:
            # no timeout: sim time stopped with the replay, and the TF must be there already
            cls.tf_final = cls.tf_buffer.lookup_transform("map", f"{NS}/base_link", rospy.Time(0))
        except Exception as e:  # noqa: BLE001 - any failure here is reported by test_3
            cls.tf_error = f"no TF map -> {NS}/base_link: {e!r}"

    @classmethod
    def replay(cls, path):
        """Play the recording in lock-step: each scan is published after the node answered the previous
        one (or 2 s passed), with /clock, /tf and /tf_static, so that a busy machine slows the test down
        but never drops scans (rosbag play would, once the node falls behind)."""
        clock_pub = rospy.Publisher("/clock", Clock, queue_size=10)
        tf_pub = rospy.Publisher("/tf", TFMessage, queue_size=100)
        static_pub = rospy.Publisher("/tf_static", TFMessage, queue_size=10, latch=True)
        scan_pub = rospy.Publisher("scan", LaserScan, queue_size=10)
        msgs = list(rosbag.Bag(path).read_messages())
        statics = [m for topic, m, _ in msgs if topic == "/tf_static"]
        deadline = time.time() + 20.0
        while scan_pub.get_num_connections() == 0 and time.time() < deadline:
            clock_pub.publish(Clock(msgs[0][2]))
            time.sleep(0.1)
        static_pub.publish(TFMessage([t for m in statics[:1] for t in m.transforms]))
        clock_pub.publish(Clock(msgs[0][2]))
        time.sleep(1.0)                                  # let the node's TF listener get the mount
        for topic, m, t in msgs:
            if rospy.is_shutdown():
                return
            clock_pub.publish(Clock(t))
            if topic == "/tf":
                tf_pub.publish(m)
            elif topic.endswith("ground_truth/pose"):
                cls._on_truth(m)
            elif topic.endswith("/scan"):
                key = round(m.header.stamp.to_sec(), 3)
                scan_pub.publish(m)
                wait_until = time.time() + 2.0
                while key not in cls.est and time.time() < wait_until:
                    time.sleep(0.002)
        time.sleep(0.5)

    @classmethod
    def _on_pose(cls, m):
        cls.est[round(m.header.stamp.to_sec(), 3)] = (m.pose.position.x, m.pose.position.y,
                                                      yaw_of(m.pose.orientation))

    @classmethod
    def _on_truth(cls, m):
        cls.truth[round(m.header.stamp.to_sec(), 3)] = (m.pose.position.x, m.pose.position.y,
                                                        yaw_of(m.pose.orientation))

    def origin(self):
        """True pose at the first scan the node processed: the SLAM map frame's origin (hector starts
        at the identity). Usually scan 0; a later one when the first scans came before the laser's TF."""
        first = min(self.est)
        self.assertIn(first, self.truth, "no ground truth for the first estimate")
        return self.truth[first]

    def to_map(self, xy):
        """Arena points -> the SLAM map frame."""
        x0, y0, th = self.origin()
        c, s = math.cos(th), math.sin(th)
        d = np.asarray(xy, float) - [x0, y0]
        return np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)

    def pairs(self):
        stamps = sorted(set(self.est) & set(self.truth))
        est = np.array([self.est[t] for t in stamps])
        gt = np.array([self.truth[t] for t in stamps])
        gt_map = self.to_map(gt[:, :2])
        gt_yaw = gt[:, 2] - self.origin()[2]
        return stamps, est, gt_map, gt_yaw

    def test_1_most_scans_processed(self):
        self.assertGreater(len(self.est), 0.8 * self.meta["n_scans"],
                           f"only {len(self.est)} of {self.meta['n_scans']} scans gave a pose")

    def test_2_trajectory_error(self):
        stamps, est, gt_map, gt_yaw = self.pairs()
        self.assertGreater(len(stamps), 100)
        err = np.linalg.norm(est[:, :2] - gt_map, axis=1)
        yaw_err = np.abs([wrap(a - b) for a, b in zip(est[:, 2], gt_yaw)])
        rms = float(np.sqrt(np.mean(err ** 2)))
        rospy.loginfo(f"replay: {len(stamps)} poses, position error rms {rms:.4f} max {err.max():.4f} m, "
                      f"yaw error max {yaw_err.max():.4f} rad")
        self.assertLess(rms, 0.05)
        self.assertLess(err.max(), 0.10)
        self.assertLess(yaw_err.max(), 0.03)

    def test_3_final_pose_and_tf(self):
        stamps, est, gt_map, gt_yaw = self.pairs()
        self.assertGreaterEqual(stamps[-1], 1000.0 + self.meta["duration"] - 0.5,
                                "the last scans were not processed")
        self.assertLess(np.linalg.norm(est[-1, :2] - gt_map[-1]), 0.05)
        self.assertLess(abs(wrap(est[-1, 2] - gt_yaw[-1])), 0.02)
        self.assertIsNotNone(self.tf_final, getattr(self, "tf_error", "no TF map -> base_link"))
        t = self.tf_final.transform.translation
        self.assertLess(math.hypot(t.x - est[-1, 0], t.y - est[-1, 1]), 0.05)

    def test_4_covariance(self):
        self.assertTrue(self.cov)
        c = self.cov[-1]
        sub = c[np.ix_([0, 1, 5], [0, 1, 5])]
        self.assertTrue(np.allclose(sub, sub.T))
        self.assertTrue(np.all(np.linalg.eigvalsh(sub) > 0))
        self.assertLess(sub[0, 0], 0.01)

    def test_5_map_walls_within_one_cell(self):
        rospy.wait_for_service("dynamic_map", 10.0)
        grid = rospy.ServiceProxy("dynamic_map", GetMap)().map
        res = grid.info.resolution
        self.assertAlmostEqual(res, 0.05, places=6)
        self.assertEqual((grid.info.width, grid.info.height), (2048, 2048))
        data = np.asarray(grid.data, np.int8).reshape(grid.info.height, grid.info.width)
        occ = np.argwhere(data == 100)                     # (row = iy, col = ix)
        self.assertGreater(len(occ), 500)
        self.assertGreater(np.count_nonzero(data == 0), 10 * len(occ))
        # Occupied cell centres, map frame -> arena frame (the map frame is the true start pose).
        ox, oy = grid.info.origin.position.x, grid.info.origin.position.y
        cx = ox + (occ[:, 1] + 0.5) * res
        cy = oy + (occ[:, 0] + 0.5) * res
        x0, y0, th = self.origin()
        c, s = math.cos(th), math.sin(th)
        occ_arena = np.stack([x0 + c * cx - s * cy, y0 + s * cx + c * cy], axis=1)
        check = map_wall_check(occ_arena, np.array(self.meta["wall_points"]),
                               np.array(self.meta["wall_segments"]), res)
        rospy.loginfo(f"replay map: {len(occ)} occupied cells, {check}")
        self.assertGreater(check["on_wall"], 0.98)          # occupied cells lie within a cell of a wall
        self.assertGreater(check["coverage"], 0.95)         # and the walls the laser saw are in the map

    def test_6_pause_and_reset_services(self):
        """Paused, the node leaves its scan and TF subscriptions (a paused robot's mapping costs nothing) and
        takes them again when resumed."""
        pause = rospy.ServiceProxy("pause_mapping", SetBool)

        def subscribed() -> set:
            subs = rosgraph.Master("/test_replay").getSystemState()[1]
            return {topic for topic, nodes in subs if "/mbzirc2020_1/hector_mapping" in nodes}
        def settles(check) -> bool:                          # the master hears of it from the node's thread
            deadline = time.time() + 5.0
            while not check(subscribed()) and time.time() < deadline:
                time.sleep(0.1)
            return check(subscribed())
        both = {rospy.resolve_name("scan"), "/tf"}
        self.assertTrue(settles(lambda subs: both <= subs))
        self.assertTrue(pause(True).success)
        self.assertTrue(settles(lambda subs: not both & subs))
        self.assertTrue(pause(True).success)                # twice: no error
        self.assertTrue(pause(False).success)
        self.assertTrue(settles(lambda subs: both <= subs))
        reset = rospy.ServiceProxy("reset_map", Trigger)
        self.assertTrue(reset().success)
        grid = rospy.ServiceProxy("dynamic_map", GetMap)().map
        self.assertTrue(np.all(np.asarray(grid.data, np.int8) == -1))


if __name__ == "__main__":
    rostest.rosrun("hector_mapping", "test_replay", ReplayTest, sys.argv)
