"""Backing out the way it came with no trusted pose (way_back.py, robot_agent._keep_off_walls_without_pose):
the trail in, the velocity back along it, and a UGV whose indoor localization stops that drives back to where
it came in on its dead reckoning, the central unit told meanwhile (data_feed NO_TRUSTED_POSE)."""
import math

import numpy as np
import pytest

from fake_backend import FakeBackend
from fake_ual import start_ugv, stop_agent
from mbzirc_agents import constants as C
from mbzirc_agents.way_back import BACK_OUT_SPEED, TRAIL_SPACING, WayBack
from test_pose_source import Localization

TOWER = [(11.4, 6.7, 24.2, 19.5, 15.0)]


def never_blocked(_u):
    return False


def test_the_trail_is_the_way_in_since_the_robot_last_came_inside():
    w = WayBack(TOWER)
    w.record((9.0, 10.0, 0.3))                        # outside: no trail
    assert not w.trail
    for x in np.arange(12.0, 16.0, 0.05):
        w.record((x, 10.0, 0.3))
    assert len(w.trail) == pytest.approx(4.0 / TRAIL_SPACING, abs=2)
    assert all(math.dist(a, b) >= TRAIL_SPACING - 1e-9 for a, b in zip(w.trail, list(w.trail)[1:]))
    w.record((14.0, 10.0, 16.0))                      # above the roof: outside again
    assert not w.trail


def test_the_velocity_goes_back_point_after_point_and_ends_where_the_trail_began():
    w = WayBack(TOWER)
    for x in np.arange(12.0, 15.0, 0.1):
        w.record((x, 10.0, 0.3))
    here = np.array([14.9, 10.0])
    steps = 0
    while True:
        v = w.velocity(here, never_blocked)
        if v is None:
            break
        assert np.linalg.norm(v) <= BACK_OUT_SPEED + 1e-9 and v[0] < 0.0
        here = here + v * 0.1
        steps += 1
        assert steps < 1000
    assert w.done and not w.trail and here[0] == pytest.approx(12.0, abs=0.3)
    assert w.take_end() == 'where it came in' and w.take_end() is None
    w.record((13.0, 10.0, 0.3))                       # a trusted pose again: a new trail, no back-out done
    assert not w.done and not w.backing


def test_a_return_ahead_on_the_way_back_ends_it():
    w = WayBack(TOWER)
    for x in np.arange(12.0, 15.0, 0.1):
        w.record((x, 10.0, 0.3))
    assert w.velocity((14.9, 10.0), lambda u: u[0] < 0.0) is None
    assert w.done and w.trail and w.take_end() == 'a laser return ahead on the way'


def test_no_trail_no_back_out():
    """Lost outside a building (or before it came in): nothing to back out along, nothing said."""
    w = WayBack(TOWER)
    w.record((5.0, 5.0, 3.0))
    assert w.velocity((5.0, 5.0), never_blocked) is None and not w.done and w.take_end() is None


def test_a_ugv_whose_localization_stops_indoors_backs_out_the_way_it_came():
    """With no trusted pose for ~lost_back_out_after s the idle UGV drives back along its trail on the UAL's
    dead reckoning, to where it came in, and holds; meanwhile its data_feed says NO_TRUSTED_POSE."""
    be = FakeBackend()
    agent, ual = start_ugv(be, (13.5, 10.0, 0.2), {'lost_back_out_after': 3.0})
    ual.follow_velocity = True
    from laser_world import LaserScene
    scene = LaserScene(be, ual, noisy=True)
    scene.boxes = [(11.4, 6.7, 11.6, 19.5), (11.4, 6.7, 24.2, 6.9)]     # facade C and B's inner faces
    loc = Localization(be, ual)
    try:
        be.clock.sleep(1.0)
        assert agent.pose_source.source == 'slam'
        for x in np.arange(13.5, 18.0, 0.05):            # driven in (a task's legs): the trail is recorded
            with ual.lock:
                ual.pos = np.array([x, 10.0 + 0.5 * math.sin(x), 0.2])
            be.clock.sleep(0.05)
        be.clock.sleep(0.5)
        loc.on = False                                   # the localization stops
        be.clock.sleep(2.0)
        assert not agent.pose_source.valid
        assert agent.data_feed().active_sub_state.startswith(C.NO_TRUSTED_POSE)
        at_loss = ual.pos.copy()
        be.clock.sleep(1.5)
        assert np.linalg.norm(ual.pos[:2] - at_loss[:2]) < 0.2      # before ~lost_back_out_after: held
        be.clock.sleep(30.0)
        assert math.dist(ual.pos[:2], (13.5, 10.0 + 0.5 * math.sin(13.5))) < 0.5, (
            ual.pos, len(agent.way_back.trail), agent.way_back.done, agent._lost_since, be.warns[-4:], agent.running_task())
        assert any('backing out the way it came' in m for m in be.warns)
        assert any('as far as where it came in' in m for m in be.warns), be.warns[-3:]
    finally:
        stop_agent(agent, ual, be, loc, scene)
