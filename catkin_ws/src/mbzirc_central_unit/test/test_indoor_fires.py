#!/usr/bin/env python3
"""rostest: a water UAV finds and puts out an indoor fire through a window (ground truth from /sim/fires).

The goals are the central unit's (its layout: room, window entry, viewpoints); the UAV has no knowledge
of which holder burns: it must find it with its thermal camera. `~explore`: the layout is the explored one
(the windows' rooms: no interior wall, no holder known) and the agent explores the floor on its laser.
`~gnss_denied`: the flight indoors must be on the SLAM pose (localization/source 'slam' while ual/gnss_status
says there is no fix).
"""
import os
import sys
import unittest

import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from sensor_msgs.msg import NavSatStatus
from std_msgs.msg import String
from ual_sim.msg import FireState

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'mbzirc_agents', 'test'))
from agent_test_utils import SimFires, pose, run  # noqa: E402

from mbzirc_central_unit import geometry as G  # noqa: E402
from mbzirc_central_unit.layout import Layout, explored_layout  # noqa: E402

UAV = 2


class TestIndoorFires(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('test_indoor_fires')
        cls.sim = SimFires()
        cls.fix_lost = False             # ual/gnss_status said STATUS_NO_FIX at least once
        cls.sources = set()              # localization/source values seen (indoor_pose says 'slam' only without a fix)
        ns = f'/mbzirc2020_{UAV}'
        rospy.Subscriber(f'{ns}/ual/gnss_status', NavSatStatus, cls._on_gnss)
        rospy.Subscriber(f'{ns}/localization/source', String, cls._on_source)

    @classmethod
    def _on_gnss(cls, msg):
        cls.fix_lost |= msg.status == NavSatStatus.STATUS_NO_FIX

    @classmethod
    def _on_source(cls, msg):
        cls.sources.add(msg.data)

    def test_indoor_fire_through_a_window(self):
        FLOOR = int(rospy.get_param('~floor', 1))
        active = [f for f in self.sim.fires.fires if f.kind == FireState.INDOOR and f.active and f.floor == FLOOR][0]
        explore = bool(rospy.get_param('~explore', False))
        layout = explored_layout() if explore else Layout()
        # the room searched is the one the strategy would search first for that holder (the test knows the
        # active holder only to pick the room; the UAV is told nothing about it); explored, the windows' rooms
        # know no interior wall: the window nearest the holder on the side its face looks to (its own room)
        p, n = active.position, active.normal
        if explore:
            rooms = layout.rooms[FLOOR]
            ahead = [i for i, r in enumerate(rooms)
                     if (r.entry[0] - p.x) * n.x + (r.entry[1] - p.y) * n.y > 0.0]
            idx = min(ahead, key=lambda i: (rooms[i].entry[0] - p.x) ** 2 + (rooms[i].entry[1] - p.y) ** 2,
                      default=None)
        else:
            idx = layout.room_for(FLOOR, (p.x, p.y, p.z))
        self.assertIsNotNone(idx, f'no room sees {active.id}')
        room = layout.rooms[FLOOR][idx]
        ex, ey, ez, eyaw = room.entry
        state, res = run(UAV, 'take_off', 'TakeOff', 60, height=ez)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        route = G.plan_route((0.0, 0.0, ez), (ex, ey, ez), 0)
        state, res = run(UAV, 'follow_path', 'FollowPath', 200, path=[pose(x, y, z, eyaw) for x, y, z in route])
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        state, res = run(UAV, 'enter_building', 'EnterBuilding', 60, floor=FLOOR, entry=pose(ex, ey, ez, eyaw))
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        path = [pose(x, y, z, yaw) for x, y, z, yaw in room.path]
        state, res = run(UAV, 'search_indoor', 'SearchIndoor', 300 if explore else 120, floor=FLOOR, path=path)
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        self.assertEqual(len(res.fire_ids), 1, res.message)
        state, res = run(UAV, 'extinguish_indoor_fire', 'ExtinguishIndoorFire', 150, fire_id=res.fire_ids[0])
        self.assertEqual(state, GoalStatus.SUCCEEDED, res.message)
        rospy.sleep(1.0)
        truth = self.sim.fire(active.id)
        self.assertTrue(res.extinguished, res.message)
        self.assertTrue(truth.extinguished, f'{active.id} progress {truth.progress:.3f} after "{res.message}", '
                                            f'{res.water_left:.2f} L left')
        self.assertEqual(self.sim.crashed, [])
        if rospy.get_param('~gnss_denied', False):
            self.assertTrue(self.fix_lost, 'the UAL never said it lost the GNSS fix indoors')
            self.assertIn('slam', self.sources, f'never on the SLAM pose (sources: {sorted(self.sources)})')


if __name__ == '__main__':
    rostest.rosrun('mbzirc_central_unit', 'test_indoor_fires', TestIndoorFires)
