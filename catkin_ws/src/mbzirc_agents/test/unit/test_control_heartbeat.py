"""Controllers and the heartbeat watchdog."""
import math

import numpy as np
import pytest

from mbzirc_agents import control as c
from mbzirc_agents import heartbeat as hb


def test_frames_round_trip():
    v = np.array([1.0, 2.0, 3.0])
    for yaw in (0.0, 1.0, -2.5):
        assert c.world_to_body(c.body_to_world(v, yaw), yaw) == pytest.approx(v)
    assert c.body_to_world((1, 0, 0), math.pi / 2) == pytest.approx([0, 1, 0], abs=1e-12)


def test_hole_centering_converges_in_closed_loop():
    ctl = c.HoleCentering(shoot_distance=1.5)
    yaw = 0.7
    uav = np.array([0.0, 0.0, 5.0])
    hole = np.array([3.0, 1.0, 6.0]) + uav * 0
    for _ in range(200):
        rel = c.world_to_body(hole - uav, yaw)
        if ctl.centred(rel):
            break
        v = ctl.velocity(rel, yaw)
        assert np.linalg.norm(v) <= ctl.vmax + 1e-9
        uav = uav + v * 0.1
    assert ctl.centred(c.world_to_body(hole - uav, yaw))


def test_hole_not_centred_when_off():
    assert not c.HoleCentering().centred((1.5, 0.5, 0.0))
    assert c.HoleCentering().centred((1.5, 0.05, -0.05))


def test_ground_centering_never_descends_off_target():
    ctl = c.GroundFireCentering(release_height=1.5)
    v = ctl.velocity((0, 0, 4), (5, 0))
    assert v[2] >= 0 and v[0] > 0
    uav = np.array([0.0, 0.0, 4.0])
    for _ in range(400):
        if ctl.ready(uav, (1.0, -1.0)):
            break
        uav = uav + ctl.velocity(uav, (1.0, -1.0)) * 0.1
    assert ctl.ready(uav, (1.0, -1.0))


def test_thermal_pixel_to_ground():
    assert c.thermal_pixel_to_ground(15.5, 15.5, 4.0) == pytest.approx([0, 0])
    off = c.thermal_pixel_to_ground(15.5, 0.0, 4.0)    # top of image = ahead
    assert off[0] > 0 and abs(off[1]) < 1e-9
    off = c.thermal_pixel_to_ground(31.0, 15.5, 4.0)   # right of image = -y
    assert off[1] < 0


def test_yaw_rate_short_way():
    assert c.yaw_rate_to(3.0, -3.0) > 0
    assert c.yaw_rate_to(0.0, 0.1) == pytest.approx(0.1)


def test_watchdog():
    w = hb.HeartbeatWatchdog(timeout=5, return_home_timeout=60)
    assert w.state(100) == hb.OK              # never seen: not lost
    w.beat(100)
    assert w.state(104) == hb.OK
    assert w.state(106) == hb.LOST
    assert w.state(166) == hb.RETURN_HOME
    w.beat(167)
    assert w.state(168) == hb.OK
    assert w.state(10) == hb.OK               # time jumped back


def test_keep_off_walls():
    from mbzirc_agents.tasks.facade import keep_off_walls
    # 0.7 m north of facade A (y = 19.5), flying south into it: the southward part is removed, pushed back
    v = keep_off_walls((15.0, 20.2, 6.0), np.array([0.2, -0.5, 0.0]), 1.0)
    assert v[1] > 0 and v[0] == pytest.approx(0.2)
    # far from the walls: unchanged
    assert list(keep_off_walls((0.0, 0.0, 3.0), np.array([0.2, -0.5, 0.1]), 1.0)) == [0.2, -0.5, 0.1]
    # 0.9 m away, moving along the wall: unchanged; moving toward it: stopped
    assert keep_off_walls((15.0, 20.4, 6.0), np.array([0.3, 0.0, 0.0]), 1.0)[1] == 0.0
    assert keep_off_walls((15.0, 20.4, 6.0), np.array([0.0, -0.4, 0.0]), 1.0)[1] == pytest.approx(0.0)


def test_keep_off_walls_ignores_a_roof_below():
    """In front of facade D's fire at (24.2, 18.8, 12.5) the UAV is above the 4.5 m extension, 0.7 m from
    its north edge: that edge is no wall at 12.5 m (it pushed the UAV off the hole for good in seed 9)."""
    from mbzirc_agents.tasks.facade import keep_off_walls
    v = np.array([0.0, -0.4, 0.0])
    assert list(keep_off_walls((25.7, 18.8, 12.5), v, 1.0)) == list(v)
    assert list(keep_off_walls((25.7, 20.3, 12.5), v, 1.0)) == list(v)
    # the tower wall 0.8 m ahead still stops a forward (-x) move there
    assert keep_off_walls((25.0, 18.8, 12.5), np.array([-0.3, 0.0, 0.0]), 1.0)[0] >= 0.0
    # at 3 m the extension's edge is a wall again
    assert keep_off_walls((25.7, 20.2, 3.0), v, 1.0)[1] > 0


def test_nearest_return_skips_nan_inf_and_too_close_beams():
    r = [float('nan'), 5.0, float('inf'), 0.05, 0.9, 3.0]
    d, a = c.nearest_return(r, -math.pi, 0.5, range_min=0.15)
    assert d == 0.9 and a == pytest.approx(-math.pi + 2.0)
    assert c.nearest_return([float('nan')] * 10, -math.pi, 0.1) == (math.inf, 0.0)
    assert c.nearest_return([], 0.0, 0.1) == (math.inf, 0.0)


def test_keep_off_the_laser_return_whatever_the_pose_says():
    """The laser sees a wall 0.6 m to the robot's left (yaw 0: +y); a velocity towards it loses that
    component, and under 0.8 x min_dist it is pushed away; other directions are untouched."""
    v = c.keep_off_return([0.5, 0.5, 0.0], 0.0, 0.9, math.pi / 2, 1.0)
    assert v == pytest.approx([0.5, 0.0, 0.0])
    v = c.keep_off_return([0.0, 0.5, 0.0], 0.0, 0.6, math.pi / 2, 1.0)
    assert v[1] < 0.0
    assert c.keep_off_return([0.0, -0.5, 0.0], 0.0, 0.6, math.pi / 2, 1.0)[1] < -0.5 + 1e-9
    assert c.keep_off_return([0.3, 0.3, 0.1], 0.0, 1.5, 0.0, 1.0) == pytest.approx([0.3, 0.3, 0.1])
    assert c.keep_off_return([0.3, 0.3, 0.1], 0.0, math.inf, 0.0, 1.0) == pytest.approx([0.3, 0.3, 0.1])
