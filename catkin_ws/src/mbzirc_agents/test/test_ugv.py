#!/usr/bin/env python3
"""rostest with ual_sim: the UGV agent's bad goals, its planned go_to and search_indoor through the door, and
extinguish_indoor_fire putting out the ground-floor fire it found. `~gnss_denied` (realistic/ugv_gnss_denied.test):
inside, the drive must have been on the SLAM pose (localization/source 'slam' while ual/gnss_status said there
was no fix)."""
import math
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from sensor_msgs.msg import NavSatStatus
from std_msgs.msg import String
from agent_test_utils import SimRobots, pose, run, wait_wall
from mbzirc_comm_objs.msg import ObjectList
from ual_sim.msg import FireStateArray, Score

from mbzirc_agents import constants as C
from mbzirc_arena.routing import segment_hits_rect


class TestUgv(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_ugv')
        cls.sim = SimRobots()
        cls.trace = []
        cls.crashed = []
        rospy.Subscriber('/sim/score', Score, lambda m: setattr(cls, 'crashed', list(m.crashed_robots)))
        assert wait_wall(lambda: 0 in cls.sim.poses, 60), 'no /sim/robots'
        rospy.Timer(rospy.Duration(0.2), lambda e: cls.trace.append(cls.sim.poses[0]))
        cls.fix_lost, cls.sources = False, set()
        rospy.Subscriber('/mbzirc2020_0/ual/gnss_status', NavSatStatus,
                         lambda m: setattr(cls, 'fix_lost', cls.fix_lost or m.status == NavSatStatus.STATUS_NO_FIX))
        rospy.Subscriber('/mbzirc2020_0/localization/source', String, lambda m: cls.sources.add(m.data))

    def test_1_bad_goals(self):
        state, res = run(0, 'search_indoor', 'SearchIndoor', 30, floor=2)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertIn('floor 2', res.message)
        state, res = run(0, 'go_to', 'GoTo', 30, waypoint=pose(float('nan'), 1, 0))
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertIn('NaN', res.message)
        state, res = run(0, 'extinguish_indoor_fire', 'ExtinguishIndoorFire', 30, fire_id=5)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertIn('unknown fire id 5', res.message)

    def test_2_enters_through_the_door(self):
        state, res = run(0, 'search_indoor', 'SearchIndoor', 400, floor=0)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.__class__.found = list(res.fire_ids)
        self.assertEqual(self.crashed, [])
        x, y, _ = self.sim.poses[0]
        tower = C.TOWER
        self.assertTrue(tower[0] < x < tower[2] and tower[1] < y < tower[3], f'UGV not inside: {x}, {y}')
        # it crossed facade B (y = 6.7) through the door (x 13.0-15.5)
        crossings = [(a, b) for a, b in zip(self.trace[:-1], self.trace[1:]) if a[1] < 6.7 <= b[1]]
        self.assertTrue(crossings)
        for a, b in crossings:
            self.assertTrue(13.0 < (a[0] + b[0]) / 2 < 15.5, f'crossed the wall at x {a[0]:.2f}')
        # outside, the drive never cut through a building footprint
        outside = [p for p in self.trace if p[1] < 6.0]
        for a, b in zip(outside[:-1], outside[1:]):
            for bld in C.BUILDINGS:
                self.assertFalse(segment_hits_rect(a, b, bld[:4]))

    def test_3_found_the_indoor_fire(self):
        """The ground-floor fire found by search_indoor is the active one (ground truth /sim/fires)."""
        fires = rospy.wait_for_message('/sim/fires', FireStateArray, 10).fires
        active = [f for f in fires if f.kind == 2 and f.floor == 0 and f.active][0]
        self.assertEqual(len(getattr(self, 'found', [])), 1)
        est = rospy.wait_for_message('/estimated_objects', ObjectList, 10).objects
        obj = [o for o in est if o.id == self.found[0]][0]
        p = obj.pose.pose.position
        self.assertLess(math.dist((p.x, p.y, p.z), (active.position.x, active.position.y, active.position.z)),
                        1.5)

    def test_4_puts_out_the_indoor_fire(self):
        """extinguish_indoor_fire on the found fire fills its container (ground truth /sim/fires)."""
        self.assertEqual(len(getattr(self, 'found', [])), 1)
        state, res = run(0, 'extinguish_indoor_fire', 'ExtinguishIndoorFire', 150, fire_id=self.found[0])
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        fires = rospy.wait_for_message('/sim/fires', FireStateArray, 10).fires
        active = [f for f in fires if f.kind == 2 and f.floor == 0 and f.active][0]
        self.assertTrue(active.extinguished, f'indoor fire progress {active.progress:.2f}: {res.message}')
        self.assertEqual(self.crashed, [])

    def test_5_drove_inside_on_the_slam_pose(self):
        """With no GNSS indoors (~gnss_denied), the UAL said so and the agent's pose came from SLAM."""
        if not rospy.get_param('~gnss_denied', False):
            self.skipTest('GNSS indoors (ugv.test); realistic/ugv_gnss_denied.test turns it off')
        self.assertTrue(self.fix_lost, 'the UAL never said it lost the GNSS fix indoors')
        self.assertIn('slam', self.sources, f'never on the SLAM pose (sources: {sorted(self.sources)})')


if __name__ == '__main__':
    rostest.rosrun('mbzirc_agents', 'test_ugv', TestUgv)
