#!/usr/bin/env python3
"""rostest with ual_sim: UAV agents' bad goals, take-off, go-to through a reserved region, preemption."""
import math
import time
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from agent_test_utils import SimRobots, client, done, pose, run, wait_wall
from mbzirc_agents.tasks.uav_motion import landing_spot, other_uav_homes
from mbzirc_comm_objs.msg import GoToGoal, TakeOffGoal
from std_msgs.msg import Header
from ual_sim.msg import Score


class TestUavMotion(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_uav_motion')
        cls.sim = SimRobots()
        cls.crashed = []
        rospy.Subscriber('/sim/score', Score, lambda m: setattr(cls, 'crashed', list(m.crashed_robots)))
        assert wait_wall(lambda: 2 in cls.sim.poses and 3 in cls.sim.poses, 60), 'no /sim/robots'

    def test_0_introspection(self):
        """Every agent publishes its SMACH structure and status under its namespace."""
        from smach_msgs.msg import SmachContainerStructure, SmachContainerStatus
        st = rospy.wait_for_message('/mbzirc2020_2/smach/container_structure', SmachContainerStructure, 30)
        self.assertIn('DEFAULT', st.children)
        self.assertIn('extinguish_facade_fire', st.children)
        self.assertIn('go_to', st.children)
        status = rospy.wait_for_message('/mbzirc2020_3/smach/container_status', SmachContainerStatus, 30)
        self.assertEqual(list(status.active_states), ['DEFAULT'])

    def test_1_bad_goals_aborted_with_message(self):
        for fields, words in (({'waypoint': pose(float('nan'), 0, 3)}, 'NaN'),
                              ({'waypoint': pose(0, 500, 3)}, 'outside the arena')):
            state, res = run(2, 'go_to', 'GoTo', 30, **fields)
            self.assertEqual(state, GoalStatus.ABORTED)
            self.assertIn(words, res.message)
        state, res = run(2, 'extinguish_facade_fire', 'ExtinguishFacadeFire', 30, fire_id=77)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertIn('unknown fire id 77', res.message)
        state, res = run(2, 'take_off', 'TakeOff', 30, height=-2.0)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertIn('height', res.message)

    def test_2_take_off_and_go_to_through_reserved_region(self):
        c2 = client(2, 'take_off', 'TakeOff')
        c3 = client(3, 'take_off', 'TakeOff')
        c2.send_goal(TakeOffGoal(height=3.0))
        c3.send_goal(TakeOffGoal(height=3.0))
        self.assertTrue(wait_wall(lambda: done(c2) and done(c3), 60))
        self.assertEqual(c2.get_state(), GoalStatus.SUCCEEDED, c2.get_result().message)
        self.assertEqual(c3.get_state(), GoalStatus.SUCCEEDED, c3.get_result().message)
        self.assertAlmostEqual(self.sim.poses[2][2], 3.0, delta=0.3)
        # UAV 3 hovers on UAV 2's way: UAV 2 must wait for the region
        from smach_msgs.msg import SmachContainerStatus
        active = set()
        sub = rospy.Subscriber('/mbzirc2020_2/smach/container_status', SmachContainerStatus,
                               lambda m: active.update(m.active_states))
        fb = []
        g2 = client(2, 'go_to', 'GoTo')
        g2.send_goal(GoToGoal(waypoint=pose(0, 8, 3)), feedback_cb=lambda f: fb.append(f.state))
        self.assertTrue(wait_wall(lambda: 'WAITING_REGION' in fb, 20), fb)
        start = self.sim.poses[2]
        time.sleep(2.0)
        self.assertLess(math.dist(self.sim.poses[2], start), 0.2, 'UAV 2 moved without its region')
        self.assertEqual(g2.get_state(), GoalStatus.ACTIVE)
        state, res = run(3, 'go_to', 'GoTo', 60, waypoint=pose(6, 3.3, 3))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.assertTrue(wait_wall(lambda: done(g2), 60))
        self.assertEqual(g2.get_state(), GoalStatus.SUCCEEDED, g2.get_result().message)
        time.sleep(0.5)
        self.assertLess(math.dist(self.sim.poses[2], (0, 8, 3)), 0.3)
        sub.unregister()
        self.assertIn('go_to', active)           # the viewer saw what the UAV was doing
        self.assertGreater(self.sim.min_distance, 1.0)
        self.assertEqual(self.crashed, [])

    def test_3_preemption_stops_the_uav(self):
        g = client(2, 'go_to', 'GoTo')
        start = self.sim.poses[2]
        g.send_goal(GoToGoal(waypoint=pose(-15, 34, 3)))
        # cancel once it is on its way (ground truth moved 3 m), whatever the real-time factor
        self.assertTrue(wait_wall(lambda: math.dist(self.sim.poses[2], start) > 3.0, 30))
        self.assertEqual(g.get_state(), GoalStatus.ACTIVE)
        g.cancel_goal()
        self.assertTrue(wait_wall(lambda: done(g), 20))
        self.assertEqual(g.get_state(), GoalStatus.PREEMPTED)
        time.sleep(0.5)
        p = self.sim.poses[2]
        time.sleep(2.0)
        self.assertLess(math.dist(self.sim.poses[2], p), 0.3, 'still moving after preemption')
        self.assertGreater(math.dist(p, (-15, 34, 3)), 5.0)
        # the agent takes new goals after a preemption
        state, res = run(2, 'go_to', 'GoTo', 60, waypoint=pose(p[0], p[1], 4.0))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)

    def test_4_land(self):
        for r in (2, 3):
            state, res = run(r, 'land', 'Land', 60)
            self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
            self.assertTrue(wait_wall(lambda: self.sim.poses[r][2] < 0.2, 3), self.sim.poses[r])
        self.assertEqual(self.crashed, [])

    def test_5_enter_building_through_a_window(self):
        state, res = run(2, 'take_off', 'TakeOff', 60, height=3.0)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        # first-floor window of facade A: x 14.5-16.5, z 6.5-8.5 at y = 19.5
        state, res = run(2, 'enter_building', 'EnterBuilding', 120, floor=1,
                         entry=pose(15.5, 21.0, 7.5, -math.pi / 2))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        time.sleep(0.5)
        x, y, z = self.sim.poses[2]
        self.assertTrue(11.6 < x < 24.0 and 6.9 < y < 19.3 and 5.0 < z < 9.5, f'not inside: {x}, {y}, {z}')
        state, res = run(2, 'go_to', 'GoTo', 60, waypoint=pose(15.5, 22.0, 7.5))   # back out
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        state, res = run(2, 'enter_building', 'EnterBuilding', 30, floor=0,
                         entry=pose(15.5, 21.0, 7.5, -math.pi / 2))
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertIn('floor 0', res.message)
        self.assertEqual(self.crashed, [])

    def test_9_heartbeat_loss(self):
        hb = rospy.Publisher('/central_unit/heartbeat', Header, queue_size=1)
        beat = rospy.Timer(rospy.Duration(0.5), lambda e: hb.publish(Header(stamp=rospy.Time.now())))
        time.sleep(1.0)
        state, res = run(2, 'take_off', 'TakeOff', 60, height=5.0)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        g = client(2, 'go_to', 'GoTo')
        g.send_goal(GoToGoal(waypoint=pose(22, -10, 5)))   # far: still flying when the loss is seen
        time.sleep(1.0)
        beat.shutdown()                                         # the central unit dies
        self.assertTrue(wait_wall(lambda: done(g), 30))
        self.assertEqual(g.get_state(), GoalStatus.ABORTED)
        self.assertIn('heartbeat', g.get_result().message)
        # let it brake (1 s of wall time is 5 s of sim time at rtf 5), then it must stay put: still flying
        # its go_to it would cover about 8 m in the next second
        time.sleep(1.0)
        p = self.sim.poses[2]
        time.sleep(1.0)
        self.assertLess(math.dist(self.sim.poses[2], p), 0.5, 'not holding after the loss')
        state, res = run(2, 'hover', 'Hover', 30, duration=1.0)
        self.assertEqual(state, GoalStatus.ABORTED)
        self.assertIn('heartbeat', res.message)
        # after ~return_home_timeout (8 s of wall time) it goes home and lands on its pad (0, 0), on the spot
        # it aims at there (~home_landing_offset, 0.5 m, off the centre away from the neighbours' pads)
        spot = landing_spot((0.0, 0.0), other_uav_homes('2'), 0.5) + (0.0,)
        self.assertTrue(wait_wall(lambda: math.dist(self.sim.poses[2], spot) < 0.3, 60),
                        f'not home: {self.sim.poses[2]}, its landing spot {spot}')
        # the heartbeat comes back: goals are accepted again
        beat = rospy.Timer(rospy.Duration(0.5), lambda e: hb.publish(Header(stamp=rospy.Time.now())))
        time.sleep(1.0)
        state, res = run(2, 'take_off', 'TakeOff', 60, height=2.0)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        beat.shutdown()
        self.assertEqual(self.crashed, [])


if __name__ == '__main__':
    rostest.rosrun('mbzirc_agents', 'test_uav_motion', TestUavMotion)
