#!/usr/bin/env python3
"""rostest: /ask_for_region and /free_regions of the region_manager node; its reservations survive a
kill -9 (respawn + state file); another node cannot free a robot's regions."""
import os
import random
import signal
import subprocess
import threading
import time
import unittest

import rosgraph
import rosnode

import rospy
import rostest
from geometry_msgs.msg import PointStamped
from mbzirc_comm_objs.srv import (AskForRegion, AskForRegionRequest, AskForRegionResponse, FreeRegions,
                                  FreeRegionsRequest)


def box_req(agent, label, lo, hi):
    r = AskForRegionRequest(agent_id=agent, label=label)
    r.min_corner, r.max_corner = PointStamped(), PointStamped()
    r.min_corner.header.frame_id = r.max_corner.header.frame_id = 'arena'
    r.min_corner.point.x, r.min_corner.point.y, r.min_corner.point.z = lo
    r.max_corner.point.x, r.max_corner.point.y, r.max_corner.point.z = hi
    return r


class TestRegions(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_regions')
        rospy.wait_for_service('/ask_for_region', 20)
        rospy.wait_for_service('/free_regions', 20)

    def setUp(self):
        self.ask = rospy.ServiceProxy('/ask_for_region', AskForRegion)
        self.free = rospy.ServiceProxy('/free_regions', FreeRegions)
        for a in ('a', 'b'):
            self.free(FreeRegionsRequest(agent_id=a, free_all=True))

    def test_overlap_refused_then_granted_after_free(self):
        self.assertTrue(self.ask(box_req('a', 'go_to', (0, 0, 0), (5, 5, 5))).success)
        self.assertFalse(self.ask(box_req('b', 'go_to', (4, 4, 4), (9, 9, 9))).success)
        self.assertTrue(self.ask(box_req('b', 'other', (6, 6, 6), (9, 9, 9))).success)
        self.assertTrue(self.free(FreeRegionsRequest(agent_id='a', label='go_to')).success)
        self.assertTrue(self.ask(box_req('b', 'go_to', (4, 4, 4), (9, 9, 9))).success)

    def test_nan_box_refused(self):
        self.assertFalse(self.ask(box_req('a', 'x', (float('nan'), 0, 0), (1, 1, 1))).success)

    def test_concurrent_overlapping_requests_never_both_granted(self):
        """Both agents race for the same corridor 50 times; at most one holds it each round."""
        for rnd in range(50):
            results = {}
            x = random.uniform(-5, 5)

            def ask(agent, lo, hi):
                results[agent] = rospy.ServiceProxy('/ask_for_region', AskForRegion)(
                    box_req(agent, 'race', lo, hi)).success
            t1 = threading.Thread(target=ask, args=('a', (x, 0, 2), (x + 4, 2, 4)))
            t2 = threading.Thread(target=ask, args=('b', (x + 2, 1, 3), (x + 6, 3, 5)))
            t1.start(); t2.start(); t1.join(); t2.join()
            self.assertFalse(results['a'] and results['b'], f'round {rnd}: both granted')
            self.assertTrue(results['a'] or results['b'], f'round {rnd}: none granted')
            for a in ('a', 'b'):
                self.free(FreeRegionsRequest(agent_id=a, label='race'))


    def test_another_node_cannot_free_a_robots_regions(self):
        self.assertTrue(self.ask(box_req('2', 'go_to', (30, 30, 0), (32, 32, 5))).success)
        out = subprocess.run(['rosservice', 'call', '/free_regions', "{agent_id: '2', label: '', free_all: true}"],
                             capture_output=True, text=True, timeout=30).stdout
        self.assertIn('success: False', out)
        self.assertFalse(self.ask(box_req('1', 'go_to', (31, 31, 1), (33, 33, 4))).success)
        self.assertTrue(self.free(FreeRegionsRequest(agent_id='2', free_all=True)).success)   # its owner may

    def test_deadlock_asks_the_lower_priority_robot_to_step_aside(self):
        """Seed 104's deadlock: 2's go_to over 3's hold and 3's go_to over 2's hold, both retried at 4 Hz;
        the manager calls robot 3's yield_region (3 has the lower priority) with 2's refused box."""
        calls = []

        def on_yield(req):
            calls.append(req)
            return AskForRegionResponse(success=True)
        srv = rospy.Service('/mbzirc2020_3/yield_region', AskForRegion, on_yield)
        try:
            self.assertTrue(self.ask(box_req('2', 'hold', (99.6, 98.0, 5.0), (101.6, 100.0, 7.0))).success)
            self.assertTrue(self.ask(box_req('3', 'hold', (100.4, 102.1, 6.4), (102.4, 104.1, 8.4))).success)
            deadline = time.time() + 20.0
            while not calls and time.time() < deadline:
                self.assertFalse(self.ask(box_req('2', 'go_to', (99.6, 98.0, 5.0), (104.0, 109.0, 7.0))).success)
                self.assertFalse(self.ask(box_req('3', 'go_to', (99.0, 94.0, 6.4), (102.4, 104.1, 8.4))).success)
                time.sleep(0.25)
            self.assertTrue(calls, 'robot 3 was never asked to step aside')
            req = calls[0]
            self.assertEqual((req.agent_id, req.label), ('2', 'go_to'))
            self.assertEqual((req.min_corner.point.x, req.max_corner.point.y, req.max_corner.point.z),
                             (99.6, 109.0, 7.0))
            # robot 3 steps up out of 2's box: 2's request is granted
            self.assertTrue(self.ask(box_req('3', 'hold', (100.4, 102.1, 7.1), (102.4, 104.1, 9.1))).success)
            self.assertTrue(self.ask(box_req('2', 'go_to', (99.6, 98.0, 5.0), (104.0, 109.0, 7.0))).success)
        finally:
            srv.shutdown()
            for a in ('2', '3'):
                self.free(FreeRegionsRequest(agent_id=a, free_all=True))

    def test_reservations_survive_kill_9(self):
        self.assertTrue(self.ask(box_req('3', 'parked', (50, 50, 0), (52, 52, 4))).success)
        master = rosgraph.Master('/test_regions')
        pid = rosnode.ServerProxy(rosnode.get_api_uri(master, '/region_manager')).getPid('/test_regions')[2]
        os.kill(pid, signal.SIGKILL)
        deadline, new_pid = time.time() + 30.0, None
        while time.time() < deadline and new_pid in (None, pid):
            time.sleep(0.3)
            try:
                new_pid = rosnode.ServerProxy(rosnode.get_api_uri(master, '/region_manager', skip_cache=True)
                                              ).getPid('/test_regions')[2]
            except Exception:
                new_pid = None
        self.assertNotIn(new_pid, (None, pid), 'the region manager did not respawn')
        rospy.wait_for_service('/ask_for_region', 20)
        self.assertFalse(self.ask(box_req('1', 'go_to', (51, 51, 1), (53, 53, 3))).success,
                         "the respawned manager forgot robot 3's reservation")
        self.assertTrue(self.free(FreeRegionsRequest(agent_id='3', free_all=True)).success)


if __name__ == '__main__':
    rostest.rosrun('shared_regions_manager', 'test_regions', TestRegions)
