"""The UAVs' downward altimeter (altimeter.py): the true height above the surface below (ground, roof,
floor slab), noise-free under `ideal`, the datasheet's noise and rare dropouts otherwise, REP 117 limits."""
import math

import numpy as np
import pytest

from ual_sim import constants as C
from ual_sim.altimeter import altimeter_reading
from ual_sim.sim import Simulation
from ual_sim.uncertainty import profile
from ual_sim.world import load_world


@pytest.fixture(scope="module")
def world():
    return load_world()


def place(sim, rid, x, y, z):
    r = sim.robots[rid]
    r.pos[:] = (x, y, z)
    return r


def test_ideal_reads_the_true_height_above_ground_roof_and_slab(world):
    s = Simulation(world, seed=1, wind=False)
    rng_state = s.rng.bit_generator.state
    assert s.altimeter(place(s, 2, 0.0, 0.0, 1.25)) == pytest.approx(1.25)       # over the ground
    ext = world.bmax[[i for i, b in enumerate(world.box_building or []) if b == "extension"]][:, 2].max()
    assert s.altimeter(place(s, 2, 30.0, 12.0, ext + 1.5)) == pytest.approx(1.5)   # over the extension's roof
    assert s.altimeter(place(s, 2, 17.0, 12.0, 6.5)) == pytest.approx(6.5 - s.world.support_height(17.0, 12.0, 6.5))
    assert s.world.support_height(17.0, 12.0, 6.5) > 4.0                          # indoors: the floor-1 slab
    assert s.altimeter(place(s, 2, 0.0, 0.0, 0.0)) == -math.inf                    # landed: below min range
    assert s.rng.bit_generator.state == rng_state     # `ideal` draws nothing: the trial stays bit for bit


def test_reading_limits_follow_rep_117():
    assert altimeter_reading(C.ALTIMETER_RANGE_MAX + 1.0) == math.inf
    assert altimeter_reading(C.ALTIMETER_RANGE_MIN / 2) == -math.inf
    assert math.isnan(altimeter_reading(math.nan))
    assert altimeter_reading(3.0) == 3.0


def test_realistic_noise_and_dropouts_match_the_datasheet_numbers():
    rng = np.random.default_rng(5)
    near = np.array([altimeter_reading(1.0, rng) for _ in range(20000)])
    far = np.array([altimeter_reading(8.0, rng) for _ in range(20000)])
    for vals, true, std in ((near, 1.0, C.ALTIMETER_NOISE_NEAR), (far, 8.0, C.ALTIMETER_NOISE_FAR)):
        ok = vals[np.isfinite(vals)]
        assert np.isnan(vals).mean() == pytest.approx(C.ALTIMETER_DROPOUT_RATE, abs=0.004)
        assert ok.mean() == pytest.approx(true, abs=0.003)
        assert ok.std() == pytest.approx(std, rel=0.05)


def test_realistic_altimeter_measures_the_truth_not_the_gnss_height(world):
    """The reported pose carries the GNSS error; the altimeter, measured from the true pose, does not."""
    s = Simulation(world, seed=3, uncertainty=profile(world.uncertainty, "realistic"), wind=False)
    r = place(s, 2, 0.0, 0.0, 1.0)
    gnss = np.array([s.reported_pose(r)[2] for _ in range(200)])
    alt = np.array([s.altimeter(r) for _ in range(200)])
    alt = alt[np.isfinite(alt)]
    assert abs(gnss.mean() - 1.0) == pytest.approx(abs(s.uncertainty.gnss_bias(2)[2]), abs=0.02)
    assert alt.mean() == pytest.approx(1.0, abs=0.02)
    assert alt.std() > 0.01                                      # noisy under `realistic`
