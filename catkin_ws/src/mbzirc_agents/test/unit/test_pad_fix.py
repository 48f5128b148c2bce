"""pad_fix: a UAV's GNSS error measured by its laser on the buildings' outer walls, from over the home pads."""
import math

import numpy as np
import pytest
from mbzirc_arena.laser import scan_points

from laser_world import ANGLE_MIN, INC, cast, wall_boxes
from mbzirc_agents.pad_fix import face_errors, gnss_error

PADS = ((0.0, 0.0), (0.0, 3.3), (-2.0, 1.65))


def observe(true_xy, z, error, yaw, rng, scans=6):
    """face_errors of `scans` noisy scans taken at true_xy (height z), placed with the reported pose
    true + error."""
    here = np.asarray(true_xy, float) + np.asarray(error, float)
    obs = []
    for _ in range(scans):
        r = cast(true_xy, yaw, wall_boxes(z), 0.01, 0.01, 0.02, rng)
        pts = scan_points(r, ANGLE_MIN, INC, (here[0], here[1], z, yaw), 0.15, 25.0)
        obs += face_errors(pts, here, z)
    return obs


@pytest.mark.parametrize('pad', PADS)
@pytest.mark.parametrize('z', (1.1, 4.1, 12.1))
def test_the_error_is_measured_on_both_axes_from_over_every_pad(pad, z):
    """Realistic seed 105: UAV 2 landed off its pad by its GNSS error three times. From over each pad, at the
    final approach's height and at the transit altitudes, the laser sees facade C and the south faces: errors
    up to 1.8 m are measured within 0.15 m on both axes, whatever the heading."""
    rng = np.random.default_rng(int(10 * z) + int(10 * pad[1]))
    for _ in range(8):
        error = rng.uniform(-1.8, 1.8, 2)
        yaw = rng.uniform(-math.pi, math.pi)
        true = np.asarray(pad) + rng.uniform(-0.5, 0.5, 2)
        err, seen = gnss_error(observe(true, z, error, yaw, rng))
        assert seen == 2 and np.all(np.abs(err - error) < 0.15), (pad, z, error, err, seen)


def test_no_wall_in_view_is_no_observation():
    """Far from the buildings (out of the laser's range) nothing is measured: the landing is flown on GNSS."""
    rng = np.random.default_rng(1)
    assert gnss_error(observe((-14.0, -10.0), 2.0, (0.5, 0.5), 0.0, rng)) [1] == 0


def test_one_face_corrects_its_normal_only():
    """Facade C alone (the south faces out of the observations): x is measured, y is left at 0."""
    err, seen = gnss_error([(np.array([-1.0, 0.0]), -0.7), (np.array([-1.0, 0.0]), -0.8)])
    assert seen == 1 and abs(err[0] - 0.75) < 1e-9 and abs(err[1]) < 1e-9
