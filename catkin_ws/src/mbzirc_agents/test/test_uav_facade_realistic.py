#!/usr/bin/env python3
"""rostest (uncertainty:=realistic): a water UAV puts out the active facade fire of floor 1 with its GNSS
error, an unknown amount of water needed and sun-heated walls (ground truth from /sim/fires and the
simulator's crash list); the agent decides "out" from its thermal camera only.

Floor 1, not 0: a floor-0 holder 0.75 m above the ground (A_4) is shot from 0.75 m, and with the
vertical GNSS error (0.4 m std) the hovering UAV hit the ground (seen on seed 3): the UAL has no
altimeter in ual_sim; that case is an open problem of the issue, not this test's subject."""
import time
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from agent_test_utils import SimFires, pose, run

from mbzirc_agents import constants as C
from mbzirc_agents.geometry import facade_standoff


class TestUavFacadeRealistic(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_uav_facade_realistic')
        cls.sim = SimFires()

    def test_water_uav_puts_out_a_facade_fire(self):
        floor1 = [f for f in self.sim.fires.fires if f.kind == 0 and f.floor == 1]
        active = [f for f in floor1 if f.active][0]
        state, res = run(2, 'take_off', 'TakeOff', 60, height=5.0)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        path = []
        for f in sorted(floor1, key=lambda f: f.active):
            (x, y, z), yaw = facade_standoff((f.position.x, f.position.y, f.position.z), C.BUILDINGS, 2.0)
            path.append(pose(x, y, z, yaw))
        state, res = run(2, 'search_facade', 'SearchFacade', 300, floor=1, path=path)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.assertEqual(len(res.fire_ids), 1, f'fires found: {res.fire_ids} ({res.message})')
        fire_id = res.fire_ids[0]
        said_out = False
        for attempt in range(2):                     # a dry tank leaves a fire for a top-up: refill once
            state, res = run(2, 'extinguish_facade_fire', 'ExtinguishFacadeFire', 200, fire_id=fire_id)
            self.assertEqual(state, GoalStatus.SUCCEEDED, f'attempt {attempt + 1}: {res.message}')
            said_out = res.extinguished
            if said_out:
                break
            state, res = run(2, 'go_home_and_refill', 'GoHomeAndRefill', 200)
            self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
            state, res = run(2, 'take_off', 'TakeOff', 60, height=5.0)
            self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        time.sleep(1.0)
        truth = self.sim.fire(active.id)
        self.assertTrue(said_out, 'the agent never judged the fire out')
        self.assertTrue(truth.extinguished, f'judged out at {truth.progress:.0%} of the '
                                            f'{truth.litres_needed:.2f} L it needs')
        self.assertEqual(self.sim.crashed, [])


if __name__ == '__main__':
    rostest.rosrun('mbzirc_agents', 'test_uav_facade_realistic', TestUavFacadeRealistic)
