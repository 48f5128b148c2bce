"""The trial's uncertainty models (uncertainty.py): their statistics, seeded and fast, and how the simulation
uses them (truth for physics, errors only in what robots sense)."""
import math

import numpy as np
import pytest

from ual_sim import constants as C
from ual_sim.sim import Simulation
from ual_sim.uncertainty import (GaussMarkov, GnssConfig, LaserConfig, PhysicsConfig, UncertaintyConfig,
                                 UncertaintyError, corrupt_scan, draw_unknowns, parse_profile, profile,
                                 TrialUncertainty, sun_heated_normals)
from ual_sim.world import load_world

DT = 1.0 / C.SIM_RATE


@pytest.fixture(scope="module")
def realistic():
    return profile(load_world().uncertainty, "realistic")


def test_gauss_markov_has_the_configured_std_and_correlation_time():
    rng = np.random.default_rng(1)
    std, tau, dt = 0.5, 30.0, 0.5
    gm = GaussMarkov(np.full(4000, std), tau, rng)      # 4000 independent processes
    x0 = gm.value.copy()
    for _ in range(int(tau / dt)):                        # one correlation time later
        gm.step(dt)
    assert gm.value.std() == pytest.approx(std, rel=0.05)  # stationary: the std does not grow or shrink
    corr = np.corrcoef(x0, gm.value)[0, 1]
    assert corr == pytest.approx(math.exp(-1.0), abs=0.04)


def test_gauss_markov_wanders_slowly():
    """Over one physics tick the bias moves by about std * sqrt(2 dt / tau): centimetres, not a jump."""
    gm = GaussMarkov(np.full(2000, 0.5), 30.0, np.random.default_rng(2))
    before = gm.value.copy()
    gm.step(DT)
    step = np.abs(gm.value - before)
    assert step.std() < 0.5 * math.sqrt(2 * DT / 30.0) * 1.2
    assert step.max() < 0.15                              # 2000 draws: within 5 sigma


def test_ideal_is_the_simulator_without_uncertainty_bit_for_bit():
    world = load_world()
    a = Simulation(load_world(), seed=5)
    b = Simulation(load_world(), seed=5, uncertainty=profile(world.uncertainty, "ideal"))
    assert b.uncertainty is None
    for s in (a, b):
        s.robots[2].take_off(3.0)
        for _ in range(60):
            s.step(DT)
    for rid in a.robots:
        assert np.array_equal(a.reported_pose(a.robots[rid]), b.reported_pose(b.robots[rid]))
        assert np.array_equal(a.laser(a.robots[rid]), b.laser(b.robots[rid]))
    from ual_sim.thermal import FORWARD
    assert np.array_equal(a.thermal_frame(a.robots[2], FORWARD), b.thermal_frame(b.robots[2], FORWARD))
    assert [f.litres_needed for f in a.fires.fires] == [f.litres_needed for f in b.fires.fires]


def test_reported_pose_error_has_the_configured_spread(realistic):
    """Over many seeds, the reported - true position error of a robot has the bias std + white std."""
    w = load_world()
    errs = []
    for seed in range(1000):
        u = TrialUncertainty(realistic, seed, [2], 1, w.bmin, w.bmax, w.box_temp, w.box_building)
        errs.append(u.gnss_fix(2))
    e = np.array(errs)
    s = Simulation(w, seed=3, uncertainty=realistic, wind=False)     # and the simulation reports it
    r = s.robots[2]
    assert np.allclose(s.reported_pose(r)[:3] - r.pos, s.uncertainty.gnss_bias(2), atol=0.3)
    g = realistic.gnss
    assert e[:, 0].std() == pytest.approx(math.hypot(g.bias_xy_std, g.white_xy_std), rel=0.1)
    assert e[:, 2].std() == pytest.approx(math.hypot(g.bias_z_std, g.white_z_std), rel=0.1)
    assert abs(e[:, :2].mean()) < 0.1


def test_reported_velocity_error_has_the_configured_spread_and_wanders(realistic):
    """The reported velocity is the truth plus a Gauss-Markov bias and white noise with the profile's stds;
    integrated over a window passage's 10 s its error is centimetres to decimetres, never zero."""
    g = realistic.gnss
    assert g.vel_white_std > 0.0 and g.vel_bias_std > 0.0
    w = load_world()
    errs, drifts = [], []
    for seed in range(600):
        u = TrialUncertainty(realistic, seed, [2], 1, w.bmin, w.bmax, w.box_temp, w.box_building)
        errs.append(u.velocity_error(2))
        climb_error = 0.0
        for _ in range(int(10.0 / DT)):
            u.step_gnss(DT)
            climb_error += u.velocity_error(2)[2] * DT
        drifts.append(climb_error)
    e = np.array(errs)
    assert e[:, 2].std() == pytest.approx(math.hypot(g.vel_bias_std, g.vel_white_std), rel=0.12)
    assert abs(e.mean()) < 0.01
    d = np.array(drifts)
    assert 0.5 * g.vel_bias_std * 10.0 < d.std() < 1.5 * math.hypot(g.vel_bias_std * 10.0, 0.1)
    s = Simulation(w, seed=3, uncertainty=realistic, wind=False)      # and the simulation reports it
    r = s.robots[2]
    assert not np.array_equal(s.reported_velocity(r), r.vel)
    ideal = Simulation(w, seed=3)
    assert np.array_equal(ideal.reported_velocity(ideal.robots[2]), ideal.robots[2].vel)


def test_a_hovering_uav_is_where_it_believes_only_in_the_reported_frame(realistic):
    """Commanded waypoints are in the reported frame: after arriving the *reported* position is the
    command (up to white noise), the true one is off by minus the bias, and it follows the bias as it
    wanders (collisions see the truth)."""
    s = Simulation(load_world(), seed=11, uncertainty=realistic, wind=False)
    r = s.robots[2]
    assert r.take_off(3.0)[0]
    for _ in range(200):
        s.step(DT)
    cmd = np.array([2.0, -3.0, 4.0])
    assert r.go_to(*cmd, 0.0)[0]
    truth, reported = [], []
    for _ in range(int(60 / DT)):
        s.step(DT)
        truth.append(r.pos.copy())
        reported.append(s.reported_pose(r)[:3])
    truth, reported = np.array(truth[-1200:]), np.array(reported[-1200:])   # the last 40 s, arrived
    assert np.abs(reported - cmd).mean(axis=0).max() < 0.1                   # it believes it is there
    off = np.linalg.norm(truth - cmd, axis=1)
    assert off.max() > 0.1                                                   # it is not
    bias = s.uncertainty.gnss_bias(2)
    assert np.allclose(truth[-1], cmd - bias, atol=0.15)        # (the position hold lags the bias a little)
    assert np.ptp(truth[:, 0]) > 0.02                                        # and it wanders with the bias


def test_landing_and_ugv_keep_their_height(realistic):
    s = Simulation(load_world(), seed=3, uncertainty=realistic, wind=False)
    ugv = s.robots[0]
    for _ in range(300):
        s.step(DT)
    assert ugv.pos[2] == pytest.approx(0.0)
    assert ugv.go_to(6.0, -4.0, 5.0, 0.0)[0]
    for _ in range(600):
        s.step(DT)
    assert ugv.pos[2] == pytest.approx(0.0) and not ugv.crashed


def test_water_a_fire_needs_is_drawn_per_fire_in_range(realistic):
    s = Simulation(load_world(), seed=7, uncertainty=realistic)
    need = np.array([f.litres_needed for f in s.fires.fires])
    lo, hi = realistic.physics.fire_water_factor
    assert np.all(need >= lo * C.LITRES_PER_FIRE) and np.all(need <= hi * C.LITRES_PER_FIRE)
    assert np.ptp(need) > 0.1
    f = next(f for f in s.fires.fires if f.active and f.kind != 1)
    i = s.fires.fires.index(f)
    s.fires.add_water(i, f.litres_needed * 0.99, 1.0)
    assert not f.extinguished
    s.fires.add_water(i, f.litres_needed * 0.02, 2.0)
    assert f.extinguished


def test_sun_heated_walls_in_limits_sun_side_hotter(realistic):
    world = load_world()
    normals = sun_heated_normals(world.bmin, world.bmax, world.box_building)
    names = np.array(world.box_names)
    assert np.allclose(normals[names == "facade_B"][0], [0, -1, 0])
    assert np.allclose(normals[names == "facade_D"][0], [1, 0, 0])
    assert np.allclose(normals[names == "roof"][0], [0, 0, 1])
    assert not normals[names == "inner_x_0"].any()
    lo, hi = realistic.physics.wall_temp_limits
    for seed in range(30):
        k = draw_unknowns(realistic.physics, np.random.default_rng(seed), 3, [1], world.bmin, world.bmax,
                          world.box_temp, world.box_building)
        heated = normals.any(axis=1)
        assert np.all((k.box_temp[heated] >= lo) & (k.box_temp[heated] <= hi))
        assert np.array_equal(k.box_temp[~heated], world.box_temp[~heated])   # interior walls unchanged
        facing = normals[heated] @ k.sun
        t = k.box_temp[heated]
        assert t[facing.argmax()] >= t[facing.argmin()] + 0.5 * realistic.physics.wall_sun_gain * max(0, facing.max()) - 1e-9
    hottest = [draw_unknowns(realistic.physics, np.random.default_rng(s), 3, [1], world.bmin, world.bmax,
                             world.box_temp, world.box_building).box_temp.max() for s in range(200)]
    assert max(hottest) > 52.0                                   # the 50-55 degC walls do happen


def test_thermal_camera_offset_and_noise_per_robot(realistic):
    from ual_sim.thermal import FORWARD
    s = Simulation(load_world(), seed=4, uncertainty=realistic)
    r = s.robots[2]
    clean = s.thermal[FORWARD].render_clean(s.world, s.fires, r.sensor_base(), r.yaw)
    frames = np.array([s.thermal_frame(r, FORWARD) for _ in range(50)])
    k = s.uncertainty.unknowns
    assert (frames - clean).mean() == pytest.approx(k.thermal_offset[2], abs=0.05)
    assert (frames - clean).std() == pytest.approx(k.thermal_noise_std[2], rel=0.05)


def test_laser_noise_and_dropout_rates():
    cfg = LaserConfig(range_std_frac=0.01, range_std_min=0.005, nan_rate=0.02, inf_rate=0.03)
    clean = np.full(200_000, 10.0)
    out = corrupt_scan(clean, cfg, np.random.default_rng(0), 0.15, 25.0)
    assert np.isnan(out).mean() == pytest.approx(0.02, abs=0.002)
    assert np.isposinf(out).mean() == pytest.approx(0.03, abs=0.002)
    fin = out[np.isfinite(out)]
    assert (fin - 10.0).std() == pytest.approx(0.1, rel=0.03)
    assert abs((fin - 10.0).mean()) < 0.002
    near = corrupt_scan(np.full(1000, 0.16), cfg, np.random.default_rng(1), 0.15, 25.0)
    assert np.nanmin(near[np.isfinite(near)]) >= 0.15               # never below range_min


def test_simulation_scans_carry_dropouts(realistic):
    s = Simulation(load_world(), seed=2, uncertainty=realistic)
    scans = np.array([s.laser(s.robots[0]) for _ in range(20)])
    assert 0.003 < np.isnan(scans).mean() < 0.03
    assert not np.array_equal(scans[0], scans[1])


@pytest.mark.parametrize("raw, match", [
    ({"gnss": {"bias_xy_std": -1}}, "bias_xy_std"),
    ({"gnss": {"tau": 0}}, "tau"),
    ({"laser": {"nan_rate": 0.7, "inf_rate": 0.6}}, "nan_rate"),
    ({"physics": {"fire_water_factor": [1.3, 0.8]}}, "fire_water_factor"),
    ({"physics": {"bogus": 1}}, "bogus"),
    ({"weather": {}}, "weather"),
])
def test_malformed_profiles_are_named(raw, match):
    with pytest.raises(UncertaintyError, match=match):
        parse_profile("x", raw)


def test_unknown_profile_is_refused_and_ideal_needs_no_entry():
    with pytest.raises(UncertaintyError, match="stormy"):
        profile({"realistic": {}}, "stormy")
    assert profile({}, "ideal").is_ideal
    assert not UncertaintyConfig("r", GnssConfig(bias_xy_std=1.0)).is_ideal
    assert not UncertaintyConfig("r", physics=PhysicsConfig(fire_water_factor=(1, 1))).is_ideal


def test_a_seeds_gnss_paths_do_not_depend_on_the_laser(realistic):
    """Helper runs of realistic seed 102 crashed in one run and not in the next: the laser's draws (how many
    depends on who subscribes, and when) came from the generator of the GNSS errors, so a seed's GNSS paths
    changed from run to run. Each model has its own generator now."""
    w = load_world()

    def paths(scans_between_steps: int) -> np.ndarray:
        u = TrialUncertainty(realistic, 102, [1, 2], 1, w.bmin, w.bmax, w.box_temp, w.box_building)
        out = []
        for _ in range(50):
            for _ in range(scans_between_steps):
                u.scan(np.full(720, 5.0), 0.1, 30.0)
            u.step_gnss(DT)
            out.append([u.gnss_fix(1), u.gnss_fix(2)])
        return np.array(out)

    assert np.array_equal(paths(0), paths(3))
    u = TrialUncertainty(realistic, 102, [1, 2], 1, w.bmin, w.bmax, w.box_temp, w.box_building)
    assert not np.allclose(u.gnss_bias(1), u.gnss_bias(2))        # and the robots' errors differ
