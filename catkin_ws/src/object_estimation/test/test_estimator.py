#!/usr/bin/env python3
"""rostest: the object_estimator node fuses three robots' sensed_objects into one track per fire."""
import math
import random
import time
import unittest

import rospy
import rostest
from mbzirc_comm_objs.msg import Object, ObjectDetection, ObjectDetectionList, ObjectList
from mbzirc_comm_objs.srv import SetObjectStatus, SetObjectStatusRequest

FIRE_A = (12.4, 19.5, 6.5)
FIRE_B = (1.0, 14.0, 0.0)


def detection(p, noise):
    d = ObjectDetection()
    d.header.frame_id = 'arena'
    d.header.stamp = rospy.Time.now()
    d.type = ObjectDetection.TYPE_FIRE
    d.pose.pose.position.x = p[0] + random.gauss(0, noise)
    d.pose.pose.position.y = p[1] + random.gauss(0, noise)
    d.pose.pose.position.z = p[2] + random.gauss(0, noise / 3)
    d.pose.pose.orientation.w = 1.0
    cov = [0.0] * 36
    cov[0], cov[7], cov[14] = 1.5, 1.5, 0.5
    d.pose.covariance = cov
    return d


class TestEstimator(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_estimator')
        cls.latest = None
        rospy.Subscriber('/estimated_objects', ObjectList, cls.on_objects)
        cls.pubs = {i: rospy.Publisher(f'/mbzirc2020_{i}/sensed_objects', ObjectDetectionList, queue_size=100)
                    for i in (1, 2, 3)}
        # the estimator is up (publishing) and subscribed to every robot before the test starts
        end = time.time() + 60
        while time.time() < end and (cls.latest is None or any(p.get_num_connections() == 0
                                                                for p in cls.pubs.values())):
            time.sleep(0.1)
        time.sleep(0.5)

    @classmethod
    def on_objects(cls, msg):
        cls.latest = msg

    def publish_round(self, with_b=True):
        for i, pub in self.pubs.items():
            objs = [detection(FIRE_A, 0.4)]
            if with_b and i == 1:
                objs.append(detection(FIRE_B, 0.3))
            bad = ObjectDetection(type=ObjectDetection.TYPE_FIRE)
            bad.pose.pose.position.x = float('nan')                 # must be skipped, not crash
            pub.publish(ObjectDetectionList(agent_id=str(i), stamp=rospy.Time.now(), objects=objs + [bad]))

    def test_one_track_per_fire_and_status(self):
        random.seed(1)
        for _ in range(20):
            self.publish_round()
            time.sleep(0.05)
        time.sleep(0.6)
        objs = [o for o in self.latest.objects if o.type == ObjectDetection.TYPE_FIRE]
        self.assertEqual(len(objs), 2, [(o.id, o.pose.pose.position) for o in objs])
        a = min(objs, key=lambda o: math.dist((o.pose.pose.position.x, o.pose.pose.position.y,
                                               o.pose.pose.position.z), FIRE_A))
        b = [o for o in objs if o.id != a.id][0]
        pa = a.pose.pose.position
        self.assertLess(math.dist((pa.x, pa.y, pa.z), FIRE_A), 0.5)
        self.assertEqual(a.status, Object.STATUS_ACTIVE)
        self.assertEqual(a.sub_type, Object.SUBTYPE_FACADE)
        self.assertEqual(b.sub_type, Object.SUBTYPE_GROUND)
        self.assertGreaterEqual(a.num_updates, 30)     # 60 sent; a loaded machine may drop some
        # status service: extinguished sticks even while robots keep seeing it
        rospy.ServiceProxy('/set_object_status', SetObjectStatus)(
            SetObjectStatusRequest(object_id=a.id, object_status=Object.STATUS_EXTINGUISHED, object_type=8))
        rospy.ServiceProxy('/set_object_status', SetObjectStatus)(
            SetObjectStatusRequest(object_id=999, object_status=1, object_type=8))   # unknown id: logged only
        for _ in range(5):
            self.publish_round(with_b=False)
            time.sleep(0.05)
        time.sleep(0.5)
        by_id = {o.id: o for o in self.latest.objects}
        self.assertEqual(by_id[a.id].status, Object.STATUS_EXTINGUISHED)
        self.assertEqual(len(by_id), 2)
        # B is not seen any more: LOST after lost_time (3 s)
        deadline = time.time() + 6
        while time.time() < deadline and {o.id: o for o in self.latest.objects}[b.id].status != Object.STATUS_LOST:
            time.sleep(0.2)
        self.assertEqual({o.id: o for o in self.latest.objects}[b.id].status, Object.STATUS_LOST)


if __name__ == '__main__':
    rostest.rosrun('object_estimation', 'test_estimator', TestEstimator)
