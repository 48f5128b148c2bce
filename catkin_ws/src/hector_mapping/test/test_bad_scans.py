#!/usr/bin/env python3
"""rostest: empty, all-NaN, wrong-increment and unknown-frame scans give no pose and a warning; good
scans before and after them are processed, and the services answer."""
import math
import sys
import time
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import PoseStamped, TransformStamped
from nav_msgs.msg import OccupancyGrid
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import LaserScan

import sim2d

NS = "mbzirc2020_1"


class BadScansTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_hector_bad_scans")
        cls.poses = []
        cls.warnings = []
        cls.maps = []
        rospy.Subscriber("slam_out_pose", PoseStamped, lambda m: cls.poses.append(m), queue_size=50)
        rospy.Subscriber("/rosout", Log, lambda m: cls.warnings.append(m.msg) if m.level >= Log.WARN else None,
                         queue_size=50)
        rospy.Subscriber("map", OccupancyGrid, lambda m: cls.maps.append(m), queue_size=2)
        cls.pub = rospy.Publisher("scan", LaserScan, queue_size=10)
        static = tf2_ros.StaticTransformBroadcaster()
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = f"{NS}/base_link"
        t.child_frame_id = f"{NS}/laser_link"
        t.transform.translation.z = 0.1
        t.transform.rotation.w = 1.0
        static.sendTransform(t)
        cls.static = static
        deadline = time.time() + 15.0
        while cls.pub.get_num_connections() == 0 and time.time() < deadline:
            time.sleep(0.1)
        time.sleep(0.5)
        cls.world = sim2d.tower_floor()

    def scan(self, ranges, frame=f"{NS}/laser_link", inc=sim2d.ANGLE_INCREMENT):
        m = LaserScan()
        m.header.stamp = rospy.Time.now()
        m.header.frame_id = frame
        m.angle_min = sim2d.ANGLE_MIN
        m.angle_increment = inc
        m.angle_max = sim2d.ANGLE_MIN + sim2d.ANGLE_INCREMENT * (sim2d.N_BEAMS - 1)
        m.range_min, m.range_max = 0.15, 25.0
        m.ranges = list(ranges)
        return m

    def good(self, x=15.0):
        return self.scan(self.world.raycast(x, 11.0, 0.0))

    def publish_and_count(self, msg, wait=1.0):
        n = len(self.poses)
        self.pub.publish(msg)
        time.sleep(wait)
        return len(self.poses) - n

    def test_bad_scans_are_skipped_and_node_keeps_working(self):
        self.assertEqual(self.publish_and_count(self.good()), 1)
        bad = {
            "empty": self.scan([]),
            "all NaN": self.scan([math.nan] * sim2d.N_BEAMS),
            "all inf": self.scan([math.inf] * sim2d.N_BEAMS),
            "wrong angle_increment": self.scan(self.world.raycast(15.0, 11.0, 0.0), inc=0.1),
            "zero angle_increment": self.scan(self.world.raycast(15.0, 11.0, 0.0), inc=0.0),
            "frame without TF": self.scan(self.world.raycast(15.0, 11.0, 0.0), frame="nowhere_link"),
        }
        for name, msg in bad.items():
            self.assertEqual(self.publish_and_count(msg, 0.6), 0, f"{name} scan gave a pose")
        self.assertEqual(self.publish_and_count(self.good(15.1)), 1, "node stopped after bad scans")
        self.assertAlmostEqual(self.poses[-1].pose.position.x, 0.1, delta=0.03)
        self.assertTrue(any("skipping scan" in w for w in self.warnings), self.warnings)
        deadline = time.time() + 5.0
        while not self.maps and time.time() < deadline:
            time.sleep(0.1)
        self.assertTrue(self.maps, "no map published")
        data = np.asarray(self.maps[-1].data, np.int8)
        self.assertGreater(np.count_nonzero(data == 100), 50)


if __name__ == "__main__":
    rostest.rosrun("hector_mapping", "test_bad_scans", BadScansTest, sys.argv)
