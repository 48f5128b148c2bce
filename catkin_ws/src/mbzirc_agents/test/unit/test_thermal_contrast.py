"""FireContrast: a locked fire's contrast to its wall on raw thermal frames (tasks/thermal_contrast.py)."""
import math

import numpy as np
import pytest

from fake_thermal import fire_frame, ring_frame
from mbzirc_agents.tasks.thermal_contrast import FireContrast, contrast, frame_of, lock_masks, warm_spot


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def feed(fc, clock, frame, dt=0.25):
    clock.t += dt
    fc.on_frame(np.asarray(frame).ravel())


@pytest.mark.parametrize('wall, gradient, offset', [(31.0, 0.0, 0.0), (52.0, 8.0, 2.0), (38.0, -6.0, -2.0)])
def test_the_contrast_is_the_fires_rise_over_its_wall_whatever_the_walls_level_and_the_cameras_offset(
        wall, gradient, offset):
    rng = np.random.default_rng(0)
    masks = lock_masks(fire_frame(60.0, wall=wall, gradient=gradient, offset=offset, noise=1.0, rng=rng), 6.0)
    assert masks is not None
    for heat in (60.0, 20.0, 8.0, 4.0, 0.0):
        c = [contrast(fire_frame(heat, wall=wall, gradient=gradient, offset=offset, noise=1.0, rng=rng), masks)
             for _ in range(50)]
        # the core's mean takes in some of the fire's cooler rim: a fixed share of the heat, never the wall's
        assert abs(np.mean(c) - heat) < 0.1 * heat + 0.3 and np.std(c) < 0.6, (heat, np.mean(c), np.std(c))


def test_noise_on_a_sun_heated_wall_never_reads_a_warm_fire_cold_nor_an_out_fire_warm():
    """Out_contrast 2 degC; pixel noise 1 degC (the camera's), a wall at 52 degC 8 degC warmer on one side."""
    rng = np.random.default_rng(1)
    clock = Clock()
    for heat, hot in ((4.0, True), (0.0, False)):
        fc = FireContrast(clock, 2.0, 0.2)
        feed(fc, clock, fire_frame(60.0, wall=52.0, gradient=8.0, noise=1.0, rng=rng))
        assert fc.lock_on_latest()
        answers = []
        for _ in range(300):
            feed(fc, clock, fire_frame(heat, wall=52.0, gradient=8.0, noise=1.0, rng=rng))
            answers.append(fc.answer())
        assert answers == [hot] * 300


def test_no_lock_no_frame_or_a_stale_frame_is_no_evidence():
    clock = Clock()
    fc = FireContrast(clock, 2.0, 0.2)
    feed(fc, clock, fire_frame(0.0))
    assert not fc.lock_on_latest()                   # nothing stands out: nothing to lock
    assert fc.answer() is None
    feed(fc, clock, fire_frame(60.0))
    assert fc.lock_on_latest()
    assert fc.answer() is None                       # no frame since the lock
    feed(fc, clock, fire_frame(0.0))
    assert fc.answer() is False
    assert fc.answer() is None                       # each answer needs a new frame
    clock.t += 5.0
    fc.contrasts.append(0.0)
    assert fc.answer() is None                       # the camera went silent


def test_frames_come_at_most_every_period_and_bad_ones_are_counted():
    clock = Clock()
    fc = FireContrast(clock, 2.0, 0.2)
    feed(fc, clock, fire_frame(60.0))
    assert fc.lock_on_latest()
    for _ in range(10):                              # 14 Hz: about one in three measured
        feed(fc, clock, fire_frame(0.0), dt=1 / 14)
    assert 3 <= len(fc.contrasts) <= 4
    clock.t += 1.0
    fc.on_frame([1.0] * 10)
    fc.on_frame([math.nan] * 1024)
    assert fc.bad == 2                               # a bad frame is no frame: the next one is read at once
    assert frame_of([math.nan] * 1024) is None and frame_of([30.0] * 1024).shape == (32, 32)


def test_a_fire_filling_the_frame_locks_only_with_a_wall_around_it():
    big = fire_frame(60.0, radius=30.0, noise=0.0)   # the whole frame is fire: no wall to measure against
    assert lock_masks(big, 6.0) is None
    core, surround = lock_masks(fire_frame(60.0, radius=14.0, noise=0.0), 6.0)
    assert core.sum() > 400 and surround.sum() >= 16 and not (core & surround).any()


def test_a_core_far_under_its_wall_is_no_evidence_not_cold():
    """The camera no longer looks at the locked area (a robot backing off a wall: -21 degC seen in a mission)."""
    clock = Clock()
    fc = FireContrast(clock, 2.0, 0.2)
    feed(fc, clock, fire_frame(60.0))
    assert fc.lock_on_latest()
    feed(fc, clock, fire_frame(-20.0))
    assert fc.answer() is None
    feed(fc, clock, fire_frame(-1.0))
    assert fc.answer() is False


def test_without_the_detector_a_warm_area_is_locked_only_when_the_frame_before_shows_it_too():
    """Realistic seed 102: a top-up's first frame after a move had a warm area 20 degC over its wall that the
    next frame did not show."""
    clock = Clock()
    fc = FireContrast(clock, 2.0, 0.2)
    feed(fc, clock, fire_frame(0.0))
    feed(fc, clock, fire_frame(20.0))
    assert not fc.lock_on_latest(steady=True)
    feed(fc, clock, fire_frame(20.0))
    assert fc.lock_on_latest(steady=True)


@pytest.mark.parametrize('outer', [17.0, 20.0, 24.0])
@pytest.mark.parametrize('off', [(0.0, -4.0), (0.0, 4.5), (-3.0, 2.0), (2.5, -1.5), (0.0, 0.0)])
def test_the_warm_spot_of_a_ring_of_flames_wider_than_the_frame_is_the_hole_it_rings(outer, off):
    """From its watering distance a holder's ring of flames fills the frame: the centroid of its part in the
    frame stayed near the image centre (a hole 4 px off read ~1 px off, or on the wrong side), so the aim
    never came onto the hole. The hole, whole in the frame, says where the fire is."""
    rng = np.random.default_rng(3)
    centre = (15.5 + off[0], 15.5 + off[1])
    for contrast_ in (200.0, 60.0, 12.0):             # the fire fading under the water
        spot = warm_spot(ring_frame(contrast_, centre, outer=outer, rng=rng), 4.0)
        assert spot is not None
        assert abs(spot[0] - centre[1]) <= 0.5 and abs(spot[1] - centre[0]) <= 0.5, (contrast_, spot)
        assert spot[2], 'the hole ringed by the flames is the fire\'s centre'


def test_the_warm_spot_of_a_whole_fire_in_the_frame_is_its_centre():
    """A fire seen whole (from farther) keeps its centroid: a disc, and a ring with its hole."""
    rng = np.random.default_rng(4)
    for frame, centre in ((fire_frame(40.0, rng=rng, radius=5.0, centre=(12.0, 19.0)), (12.0, 19.0)),
                          (ring_frame(80.0, (17.0, 13.0), outer=8.0, hole=3.0, rng=rng), (17.0, 13.0))):
        spot = warm_spot(frame, 4.0)
        assert abs(spot[0] - centre[1]) <= 0.5 and abs(spot[1] - centre[0]) <= 0.5, spot
        assert spot[2]


def test_a_fire_cut_by_the_frames_edge_around_no_hole_is_not_whole():
    """Its centroid lies short of its centre, towards the image's: the aim keeps the detector's bearing then."""
    spot = warm_spot(fire_frame(40.0, rng=np.random.default_rng(5), radius=8.0, centre=(15.5, -1.0)), 4.0)
    assert spot is not None and not spot[2]


def _rendered_frame(pos, yaw_deg, progress, seed=117):
    """ual_sim's realistic thermal frame of a UAV at pos facing yaw_deg, with in1_w (17.7, 8.5, 6.5, facing
    -x) burning at `progress` (the referee's renderer: the world the robots are judged in)."""
    from ual_sim.sim import Simulation
    from ual_sim.uncertainty import profile
    from ual_sim.world import load_world
    from sim_ual import indoor_fire
    world = load_world()
    sim = Simulation(world, seed=seed, uncertainty=profile(world.uncertainty, 'realistic'))
    fire = sim.fires.fires[indoor_fire(sim, 'in1_w')]
    fire.litres = progress * fire.litres_needed
    r = next(r for r in sim.robots.values() if r.is_uav and r.water > 0)
    r.state = 3
    r.pos, r.yaw = np.array(pos, dtype=float), math.radians(yaw_deg)
    return np.asarray(sim.thermal_frame(r, True), dtype=float).reshape(32, 32)


@pytest.mark.parametrize('seed', [3, 117])
@pytest.mark.parametrize('y', [7.4, 7.6, 7.8, 8.0])
def test_realistic_117_a_warm_wall_beside_a_windows_cold_sky_is_no_ring_of_flames(y, seed):
    """From a watering pose 0.5-1.1 m beside in1_w, a look 30 deg away from it sees the interior wall warm over
    facade B's window (the cold sky): the noise pixels it encloses are no hole, so no ring is taken there
    (found while looking into seed 117's miss at in1_w; the renderer's draws of seed 3 show it here)."""
    from mbzirc_agents.tasks.thermal_contrast import pixel_bearing, ringed_spot
    for yaw in (-45, -30, -20):
        found = ringed_spot(_rendered_frame((16.2, y, 6.65), yaw, 0.915, seed), 4.0)
        assert found is None, f'a ring {yaw + math.degrees(pixel_bearing(found[0].column, 33.0)):+.0f} deg'


@pytest.mark.parametrize('seed', [3, 117])
@pytest.mark.parametrize('progress', [0.0, 0.915, 0.97])
def test_the_ring_of_a_fire_nearly_out_seen_aside_is_found_at_its_bearing(progress, seed):
    from mbzirc_agents.tasks.thermal_contrast import pixel_bearing, ringed_spot
    for y, yaw in ((7.6, 30), (7.8, 20), (8.0, 20), (8.5, 0)):
        found = ringed_spot(_rendered_frame((16.2, y, 6.65), yaw, progress, seed), 4.0)
        assert found is not None, (y, yaw)
        bearing = yaw + math.degrees(pixel_bearing(found[0].column, 33.0))
        assert bearing == pytest.approx(math.degrees(math.atan2(8.5 - y, 1.5)), abs=3.0)
