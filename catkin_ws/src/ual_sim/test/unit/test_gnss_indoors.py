"""No GNSS indoors (uncertainty.py, `gnss.denied_indoors`): where the fix is lost, how the dead-reckoned
pose drifts, what the controller does with it, and that it is off unless asked for."""
import math

import numpy as np
import pytest

from ual_sim import constants as C
from ual_sim.sim import Simulation
from ual_sim.uncertainty import (GnssConfig, GnssError, UncertaintyError, building_volumes, inside_building,
                                 parse_profile, profile, with_gnss_denied_indoors)
from ual_sim.world import load_world

DT = 1.0 / C.SIM_RATE
INSIDE_FLOOR_1 = np.array([14.0, 12.5, 7.5])     # tower first floor, west room (free of walls)
OUTSIDE_WINDOW_C1 = np.array([9.0, 12.5, 7.5])   # in front of facade C's first-floor window (y 11.5-13.5)


@pytest.fixture(scope="module")
def world():
    return load_world()


def denied(world, name):
    return with_gnss_denied_indoors(profile(world.uncertainty, name), True)


def test_building_volumes_are_the_outline_below_the_roof(world):
    v = building_volumes(world.bmin, world.bmax, world.box_building)
    tower = v[np.argmax(v[:, 4])]
    assert tower.tolist() == pytest.approx([11.4, 6.7, 24.2, 19.5, 15.0])   # roof, not the roof structure (18)
    assert sorted(v[:, 4].tolist()) == pytest.approx([4.5, 15.0])             # the extension's roof
    assert inside_building(INSIDE_FLOOR_1, v)
    assert inside_building([14.0, 12.5, 14.9], v)
    assert not inside_building([14.0, 12.5, 15.5], v)       # above the roof
    assert not inside_building(OUTSIDE_WINDOW_C1, v)        # in front of the window
    assert not inside_building([30.0, 12.0, 5.0], v)        # above the extension
    assert inside_building([30.0, 12.0, 2.0], v)


def test_denied_in_the_realistic_profile_only(world):
    assert not profile(world.uncertainty, "ideal").gnss.denied_indoors
    assert profile(world.uncertainty, "realistic").gnss.denied_indoors


def test_profile_switch_and_its_errors():
    cfg = parse_profile("p", {"gnss": {"denied_indoors": True, "indoor_scale_std": 0.05}})
    assert cfg.gnss.denied_indoors and cfg.gnss.enabled and not cfg.is_ideal
    assert cfg.gnss.indoor_scale_std == 0.05
    assert not with_gnss_denied_indoors(cfg, False).gnss.denied_indoors
    assert with_gnss_denied_indoors(cfg, None) is cfg
    for raw, word in (({"denied_indoors": "yes"}, "denied_indoors"), ({"indoor_vel_bias_tau": 0}, "indoor_vel_bias_tau"),
                      ({"indoors": True}, "unknown keys"), ({"indoor_scale_std": -1}, "indoor_scale_std")):
        with pytest.raises(UncertaintyError, match=word):
            parse_profile("p", {"gnss": raw})


def test_dead_reckoning_drift_grows_as_configured():
    """2000 robots fly 30 s indoors at 1 m/s along x: the error's spread is the integrated Gauss-Markov
    velocity bias plus the scale error times the distance; the height keeps its error."""
    cfg = GnssConfig(denied_indoors=True)
    rng = np.random.default_rng(4)
    n, t_in, v = 2000, 30.0, np.array([1.0, 0.0, 0.0])
    errs, start = [], []
    for _ in range(n):
        g = GnssError(cfg, rng)
        start.append(g.error.copy())
        for _ in range(int(t_in / 0.1)):
            g.step(0.1, True, v)
        assert g.denied
        errs.append(g.fix())
    drift = np.array(errs) - np.array(start)
    s, tau = cfg.indoor_vel_bias_std, cfg.indoor_vel_bias_tau
    var_bias = 2 * s * s * tau * tau * (t_in / tau - 1 + math.exp(-t_in / tau))   # integral of an OU process
    var_scale = (cfg.indoor_scale_std * t_in) ** 2
    assert drift[:, 0].std() == pytest.approx(math.sqrt(var_bias + var_scale), rel=0.1)
    assert drift[:, 1].std() == pytest.approx(math.sqrt(var_bias), rel=0.1)
    assert np.all(drift[:, 2] == 0.0)
    assert abs(drift[:, 0].mean()) < 0.1


def test_fix_lost_inside_continuous_then_regained_with_the_bias(world):
    """Through a window into the tower and back: no jump when the fix is lost (the dead reckoning starts
    where the last fix was), the status says so, and outside the error is the GNSS bias again."""
    s = Simulation(load_world(), seed=5, uncertainty=denied(world, "realistic"), wind=False)
    r = s.robots[2]
    r.pos[:] = OUTSIDE_WINDOW_C1 - (0, 0, 7.5)
    r.goal = r.pos.copy()
    assert r.take_off(7.5)[0]
    for _ in range(int(8 / DT)):
        s.step(DT)
    assert s.gnss_valid(r)
    errors, valid = [], []
    for target in (INSIDE_FLOOR_1, INSIDE_FLOOR_1 + (0, 0, 0.01), OUTSIDE_WINDOW_C1):
        assert r.go_to(*(target + s.uncertainty.gnss_bias(2)), 0.0)[0]     # command where truth should go
        for _ in range(int(12 / DT)):
            s.step(DT)
            errors.append(s.uncertainty.gnss_bias(2).copy())
            valid.append(s.gnss_valid(r))
    assert not r.crashed, r.crash_reason
    valid = np.array(valid)
    lost = int(np.argmin(valid))
    back = lost + int(np.argmax(valid[lost:]))
    assert 0 < lost < back                                  # lost inside, regained outside
    assert inside_building(r.pos, s.uncertainty.buildings) is False
    e = np.array(errors)
    steps = np.linalg.norm(np.diff(e, axis=0), axis=1)
    assert steps[lost - 1] < 0.01                            # the bias wanders by mm per tick: no jump on entry
    assert np.linalg.norm(e[back - 1] - e[lost - 1]) > 0.02  # it drifted meanwhile
    assert np.allclose(e[-1], s.uncertainty.gnss[2].bias.value)   # outside: the GNSS bias again


def test_a_hovering_uav_indoors_drifts_with_its_dead_reckoning(world):
    """The controller holds the *reported* position: indoors the UAV believes it hovers while in truth it
    drifts by minus the dead-reckoned error (collisions see the truth)."""
    s = Simulation(load_world(), seed=9, uncertainty=denied(world, "ideal"), wind=False)
    r = s.robots[2]
    r.pos[:] = INSIDE_FLOOR_1 - (0, 0, 2.0)
    r.goal = r.pos.copy()
    assert r.take_off(2.0)[0]
    for _ in range(int(5 / DT)):
        s.step(DT)
    assert not s.gnss_valid(r)
    cmd = s.reported_pose(r)[:3].copy()
    assert r.go_to(*cmd, 0.0)[0]
    start = r.pos.copy()
    for _ in range(int(30 / DT)):
        s.step(DT)
    assert not r.crashed, r.crash_reason
    reported = s.reported_pose(r)[:3]
    assert np.allclose(reported, cmd, atol=0.05)                     # it believes it holds
    moved = np.linalg.norm((r.pos - start)[:2])
    assert moved > 0.1                                               # it does not (0.02 m/s bias std, 30 s)
    assert np.allclose(r.pos, cmd - s.uncertainty.gnss_bias(2), atol=0.05)


def test_outdoors_nothing_changes_when_the_switch_is_on(world):
    """A robot that never enters a building reports bit for bit the same poses with or without the model
    (the model draws only when a fix is lost)."""
    off = Simulation(load_world(), seed=3, uncertainty=with_gnss_denied_indoors(profile(world.uncertainty, "realistic"), False),
                     wind=False)
    on = Simulation(load_world(), seed=3, uncertainty=denied(world, "realistic"), wind=False)
    for s in (off, on):
        s.robots[2].take_off(3.0)
    for _ in range(300):
        for s in (off, on):
            s.step(DT)
        for rid in off.robots:
            assert np.array_equal(off.reported_pose(off.robots[rid]), on.reported_pose(on.robots[rid]))
            assert on.gnss_valid(on.robots[rid])


def test_launch_switch_overrides_the_profile_or_keeps_it():
    from ual_sim.node import SimNode
    parse = SimNode._denied_indoors_override
    assert parse("") is None and parse(None) is None
    assert parse(True) is True and parse(False) is False
    assert parse("true") is True and parse("False") is False
    assert parse("maybe") is None                        # logged as an error; the profile's value stays
