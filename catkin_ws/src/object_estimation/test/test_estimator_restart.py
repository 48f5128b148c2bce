#!/usr/bin/env python3
"""rostest: the object estimator survives kill -9 with its tracks (ids, statuses) and never reuses an id;
a corrupt state file is reported with a clear error and the estimator starts empty and keeps running."""
import os
import shutil
import time
import unittest
from xmlrpc.client import ServerProxy

import rosgraph
import rospy
import rostest
from mbzirc_comm_objs.msg import Object, ObjectDetection, ObjectDetectionList, ObjectList
from mbzirc_comm_objs.srv import SetObjectStatus, SetObjectStatusRequest
from rosgraph_msgs.msg import Log

NODE = '/object_estimator'
FIRES = {'a': (12.4, 19.5, 6.5), 'b': (1.0, 14.0, 0.0), 'c': (40.0, 40.0, 0.0)}


def detection(p, typ=ObjectDetection.TYPE_FIRE):
    d = ObjectDetection(type=typ)
    d.header.frame_id = 'arena'
    d.header.stamp = rospy.Time.now()
    d.pose.pose.position.x, d.pose.pose.position.y, d.pose.pose.position.z = p
    d.pose.pose.orientation.w = 1.0
    return d


class TestEstimatorRestart(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_estimator_restart')
        cls.msgs = []          # (wall time received, {id: status})
        cls.errors = []        # (wall time, msg) of the estimator's ERROR lines
        rospy.Subscriber('/estimated_objects', ObjectList, cls.on_objects)
        rospy.Subscriber('/rosout', Log, cls.on_log)
        cls.pubs = {i: rospy.Publisher(f'/mbzirc2020_{i}/sensed_objects', ObjectDetectionList, queue_size=100)
                    for i in (1, 2)}
        cls.state_file = rospy.get_param(NODE + '/state_file')
        end = time.time() + 60
        while time.time() < end and (not cls.msgs or any(p.get_num_connections() == 0 for p in cls.pubs.values())):
            time.sleep(0.1)
        time.sleep(0.5)

    @classmethod
    def tearDownClass(cls):
        time.sleep(1.5)             # let the estimator write its last changes, then nothing changes any more
        shutil.rmtree(os.path.dirname(cls.state_file), ignore_errors=True)

    @classmethod
    def on_objects(cls, msg):
        cls.msgs.append((time.monotonic(), {o.id: o.status for o in msg.objects}))

    @classmethod
    def on_log(cls, msg):
        if msg.name == NODE and msg.level >= Log.ERROR:
            cls.errors.append((time.monotonic(), msg.msg))

    def send(self, names, rounds=6, robot=1):
        for _ in range(rounds):
            objs = [detection(FIRES[n]) for n in names]
            self.pubs[robot].publish(ObjectDetectionList(agent_id=str(robot), stamp=rospy.Time.now(), objects=objs))
            time.sleep(0.05)

    def latest_after(self, t, timeout=30.0, cond=lambda objs: True):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            later = [objs for tm, objs in self.msgs if tm > t and cond(objs)]
            if later:
                return later[0]
            time.sleep(0.1)
        self.fail(f'no /estimated_objects after the restart within {timeout} s')

    def kill_and_wait_respawn(self, before_respawn=None):
        master = rosgraph.Master('/test_estimator_restart')
        pid = ServerProxy(master.lookupNode(NODE)).getPid('/t')[2]
        os.kill(pid, 9)
        t_kill = time.monotonic()
        if before_respawn:
            before_respawn()
        end = t_kill + 40
        while time.monotonic() < end:
            try:
                new = ServerProxy(master.lookupNode(NODE)).getPid('/t')[2]
                if new != pid:
                    return t_kill
            except Exception:
                pass
            time.sleep(0.2)
        self.fail('the estimator was not respawned')

    def test_1_tracks_survive_kill_with_ids_and_statuses(self):
        self.send(['a', 'b'])
        self.send(['a'], robot=2)
        objs = self.latest_after(time.monotonic(), cond=lambda o: len(o) == 2)
        fire_a = min(objs)          # created first
        rospy.ServiceProxy('/set_object_status', SetObjectStatus)(
            SetObjectStatusRequest(object_id=fire_a, object_status=Object.STATUS_EXTINGUISHED, object_type=8))
        before = self.latest_after(time.monotonic(),
                                   cond=lambda o: o.get(fire_a) == Object.STATUS_EXTINGUISHED)
        self.assertEqual(sorted(before.values()), [Object.STATUS_ACTIVE, Object.STATUS_EXTINGUISHED])
        time.sleep(1.0)             # > ~save_period: the last position updates are on disk too
        self.assertTrue(os.path.exists(self.state_file))
        t_kill = self.kill_and_wait_respawn()
        after = self.latest_after(t_kill)
        self.assertEqual(after, before, 'tracks after the restart differ (ids / statuses)')
        # ids continue: a new fire gets a new id; known fires still associate to their old tracks
        self.send(['a', 'b', 'c'])
        now = self.latest_after(time.monotonic(), cond=lambda o: len(o) == 3)
        new_ids = set(now) - set(before)
        self.assertEqual(len(new_ids), 1, now)
        self.assertGreater(new_ids.pop(), max(before))
        self.assertEqual(now[fire_a], Object.STATUS_EXTINGUISHED)

    def test_2_corrupt_state_file_is_reported_and_estimator_starts_empty(self):
        def corrupt():
            with open(self.state_file, 'w') as f:
                f.write('{"format": "mbzirc_agents/estimator_tracks", "version": 1, "sav')
        t_kill = self.kill_and_wait_respawn(before_respawn=corrupt)
        after = self.latest_after(t_kill)
        self.assertEqual(after, {})
        end = time.monotonic() + 10
        while time.monotonic() < end and not [m for t, m in self.errors if t > t_kill]:
            time.sleep(0.1)
        errs = [m for t, m in self.errors if t > t_kill]
        self.assertTrue(errs and 'cannot resume' in errs[0] and 'corrupt' in errs[0], errs)
        self.send(['b'])            # and it keeps working
        self.latest_after(time.monotonic(), cond=lambda o: len(o) == 1)


if __name__ == '__main__':
    rostest.rosrun('object_estimation', 'estimator_restart', TestEstimatorRestart)
