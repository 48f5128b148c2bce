"""extinguish_facade_fire safety against the fake UAL: laser clamp, hole-jump abort, stop when cold.

Why: the centring loop once drifted into the wall (aiming on the hole, then on a metres-off estimate)
and always emptied the tank. Here the UAV sits at the standoff of a holder on the west face of the
building (x = 11.4); detections, laser and thermal answers are scripted.
"""
import math
import threading
import time

import numpy as np
import pytest
from mbzirc_comm_objs.msg import (ExtinguishFacadeFireGoal, Object, ObjectDetection, ObjectDetectionList,
                                  ObjectList, TakeOffGoal)
from mbzirc_comm_objs.srv import CheckFireResponse
from sensor_msgs.msg import LaserScan

from fake_backend import FakeBackend
from fake_ual import start_uav
from mbzirc_agents import constants as C
from mbzirc_agents.control import HoleCentering, front_distance

HOLDER = (11.4, 8.5, 6.0)          # west face; standoff at x = 11.4 - 1.5, facing +x (yaw 0)


class Scene:
    """Publishes a hole and a laser scan at 10 Hz into the agent, answers CheckFire."""

    def __init__(self, be, ual):
        self.be, self.ual = be, ual
        self.hole = np.array(HOLDER)
        self.wall = None                          # laser distance ahead (None: no scan)
        self.hot = lambda: True
        self.stop = False
        be.handlers['thermal_detection/fire_detected'] = lambda r: CheckFireResponse(fire_detected=self.hot())
        threading.Thread(target=self._loop, daemon=True).start()

    def _loop(self):
        while not self.stop:
            subs = self.be.subs
            if 'sensed_objects' in subs:
                d = ObjectDetection(type=C.TYPE_HOLE)
                d.header.frame_id = 'arena'
                d.pose.pose.position.x, d.pose.pose.position.y, d.pose.pose.position.z = self.hole
                d.scale.x = 0.15
                subs['sensed_objects'](ObjectDetectionList(objects=[d]))
            if 'scan' in subs and self.wall is not None:
                inc = 2 * math.pi / 720
                a = -math.pi + inc * np.arange(720)
                r = np.where(np.abs(a) < 1.2, self.wall / np.maximum(np.cos(a), 1e-3), np.inf)
                subs['scan'](LaserScan(angle_min=-math.pi, angle_increment=inc, ranges=list(r)))
            time.sleep(0.1)


@pytest.fixture
def scene():
    be = FakeBackend()
    agent, ual = start_uav(be, speedup=4.0)
    sc = Scene(be, ual)
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=3.0))
    assert s.wait(10) == 'succeeded'
    o = Object(id=5, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_FACADE, status=C.STATUS_ACTIVE)
    o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = HOLDER
    o.pose.pose.orientation.w = 1.0
    be.handlers['/set_object_status'] = lambda r: sc.statuses.append(r.object_status) or type('R', (), {})()
    sc.statuses = []
    be.subs['/estimated_objects'](ObjectList(objects=[o]))
    yield agent, ual, be, sc
    sc.stop = True
    be.shutdown = True
    ual.stop = True
    agent.shutdown()


def extinguish(be, timeout=30):
    s = be.servers['extinguish_facade_fire_action']
    s.send(ExtinguishFacadeFireGoal(fire_id=5))
    return s, s.wait(timeout)


def test_stops_pumping_when_the_fire_goes_cold(scene):
    agent, ual, be, sc = scene
    ual.speedup = 1.0                              # real flow: C.COLD_CHECKS answers take 3 s of water
    sc.hot = lambda: ual.water > 1.8               # out after 0.2 L
    s, status = extinguish(be)
    assert status == 'succeeded', s.text
    assert s.result.extinguished and 'extinguished' in s.result.message
    assert s.result.water_left > 0.5 and ual.water > 0.5      # did not empty the tank
    assert not ual.pump
    assert sc.statuses == [C.STATUS_EXTINGUISHED]


def test_cold_answers_off_the_hole_do_not_count(scene):
    """The hole moves aside once water flows and the UAV cannot follow (frozen): the pump stops and the
    thermal camera, off the fire, answers "no fire"; that must not make the fire extinguished."""
    agent, ual, be, sc = scene
    agent.p['extinguish_timeout'] = 8.0
    sc.hot = lambda: bool(ual.pump)               # seen only while centred and pumping

    def move_hole_once_pumping():
        while not ual.pump and not sc.stop:
            time.sleep(0.02)
        ual.speedup = 0.0                          # frozen: it cannot re-centre, no more water flows
        sc.hole = np.array(HOLDER) + np.array([0.0, 0.45, 0.0])
    threading.Thread(target=move_hole_once_pumping, daemon=True).start()
    s, status = extinguish(be)
    assert status == 'aborted' and 'not done after' in s.result.message, (status, s.result.message)
    assert sc.statuses == []


def test_hot_fire_empties_the_tank_and_stays_active(scene):
    agent, ual, be, sc = scene
    s, status = extinguish(be)
    assert status == 'succeeded' and not s.result.extinguished and ual.water <= 0.1
    assert sc.statuses == []


def test_hole_jump_aborts(scene):
    agent, ual, be, sc = scene
    s = be.servers['extinguish_facade_fire_action']
    s.send(ExtinguishFacadeFireGoal(fire_id=5))
    deadline = time.monotonic() + 15
    while not ual.pump and time.monotonic() < deadline:     # locked on the hole and shooting
        time.sleep(0.05)
    assert ual.pump
    sc.hole = np.array(HOLDER) + [0.0, 2.0, 0.0]             # the "hole" is now 2 m to the side
    assert s.wait(10) == 'aborted'
    assert 'jumped' in s.result.message
    assert not ual.pump


def test_laser_clamps_forward_motion_whatever_the_hole_says(scene):
    agent, ual, be, sc = scene
    agent.p['centering_timeout'] = 3.0
    sc.hole = np.array(HOLDER) + [2.5, 0.0, 0.0]             # an estimate 2.5 m behind the wall
    sc.wall = 1.2                                            # the laser: the wall is 1.2 m ahead
    be.pubs['ual/set_velocity'].clear()
    s, status = extinguish(be)
    assert status == 'aborted' and 'centre' in s.result.message
    vx = [m.twist.linear.x for m in be.pubs['ual/set_velocity']]   # yaw 0: world x = forward
    assert len(vx) > 10
    assert max(vx) <= 0.8 * (1.2 - 1.0) + 1e-6


def test_hole_centering_clamp_and_front_distance():
    ctl = HoleCentering(shoot_distance=1.5)
    assert ctl.velocity((4.0, 0, 0), 0.0)[0] == pytest.approx(0.5)          # unclamped: full speed on
    assert ctl.velocity((4.0, 0, 0), 0.0, 1.2, 1.0)[0] == pytest.approx(0.16)
    assert ctl.velocity((4.0, 0, 0), 0.0, 0.7, 1.0)[0] < 0                  # too close: backs off
    v = ctl.velocity((4.0, 0, 0), math.pi / 2, 1.2, 1.0)
    assert v[1] == pytest.approx(0.16) and abs(v[0]) < 1e-9
    inc = 2 * math.pi / 720
    a = -math.pi + inc * np.arange(720)
    r = 1.5 / np.cos(a)
    r[360] = np.inf                                    # the front beam passes through the hole
    r[np.abs(a) > 1.0] = np.nan
    assert front_distance(r, -math.pi, inc) == pytest.approx(1.5)
    assert front_distance([np.inf] * 720, -math.pi, inc) == math.inf
    assert front_distance([], -math.pi, inc) == math.inf
    assert front_distance([1.0] * 10, -math.pi, 0.0) == math.inf
