#!/usr/bin/env python3
"""rostest: 10 000 scattered detections (a flooding publisher) do not stall /estimated_objects, and the
estimator still turns a real fire's detections into a track afterwards."""
import time
import unittest

import numpy as np
import rospy
import rostest
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList, ObjectList

from mbzirc_arena import messages as C


def detections(points):
    out = ObjectDetectionList(agent_id='1')
    for p in points:
        d = ObjectDetection(type=C.TYPE_FIRE)
        d.header.frame_id = 'arena'
        d.pose.pose.position.x, d.pose.pose.position.y, d.pose.pose.position.z = map(float, p)
        d.pose.pose.orientation.w = 1.0
        out.objects.append(d)
    return out


class TestEstimatorFlood(unittest.TestCase):
    def test_flood_does_not_stall_the_output(self):
        rospy.init_node('test_estimator_flood')
        walls, last = [], {}

        def on_objects(msg):
            walls.append(time.monotonic())
            last['msg'] = msg

        rospy.Subscriber('/estimated_objects', ObjectList, on_objects, queue_size=10)
        pub = rospy.Publisher('/mbzirc2020_1/sensed_objects', ObjectDetectionList, queue_size=200)
        deadline = time.monotonic() + 30
        while (not walls or pub.get_num_connections() == 0) and time.monotonic() < deadline:
            time.sleep(0.1)
        self.assertTrue(walls, 'no /estimated_objects before the flood')
        rng = np.random.default_rng(0)
        start = time.monotonic()
        for _ in range(100):                       # 100 lists x 100 detections, far apart: 10 000 tracks
            pub.publish(detections(rng.uniform(0, 5000, (100, 3))))
            time.sleep(0.02)
        time.sleep(5.0)
        end = time.monotonic()
        pts = [start] + [w for w in walls if start <= w <= end] + [end]
        worst = max(b - a for a, b in zip(pts, pts[1:]))
        self.assertLess(worst, 2.0, f'/estimated_objects paused {worst:.1f} s during the flood')
        # function: a real fire seen after the flood still becomes one track, once the estimator has worked
        # through the flood it queued (seconds under load: each detection is a few small matrix operations)
        deadline, objs = time.monotonic() + 60.0, []
        while not objs and time.monotonic() < deadline:
            pub.publish(detections([(12.0, 20.0, 5.0)]))
            time.sleep(0.3)
            objs = [o for o in last['msg'].objects
                    if np.hypot(o.pose.pose.position.x - 12.0, o.pose.pose.position.y - 20.0) < 1.0]
        self.assertEqual(len(objs), 1, 'the fire seen after the flood has no track')


if __name__ == '__main__':
    rostest.rosrun('object_estimation', 'test_estimator_flood', TestEstimatorFlood)
