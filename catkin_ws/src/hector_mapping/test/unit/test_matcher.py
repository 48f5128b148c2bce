"""Gauss-Newton matching on one level: recovers a known offset, clamps rotation steps."""
import numpy as np
import pytest

import sim2d
from hector_mapping.geometry import compose, inverse, transform_points
from hector_mapping.grid import GridLevel
from hector_mapping.matcher import best_rotation, match_level, residual
from hector_mapping.scan import ScanFilter, scan_to_points

WORLD = sim2d.tower_floor()
START = np.array([15.0, 11.0, 0.3])


def points_at(pose):
    r = WORLD.raycast(*pose)
    return scan_to_points(r, sim2d.ANGLE_MIN, sim2d.ANGLE_INCREMENT, 0.15, 25.0, ScanFilter())


def level_with_first_scan(res=0.05):
    g = GridLevel(int(30 / res), res, (-15.0, -15.0))
    for _ in range(3):
        g.update(np.zeros(2), points_at(START))
    return g


@pytest.mark.parametrize("offset", [(0.06, -0.04, 0.03), (-0.05, 0.05, -0.05), (0.0, 0.08, 0.0)])
def test_recovers_a_small_offset(offset):
    g = level_with_first_scan()
    true_rel = np.array(offset)
    pts = points_at(compose(START, true_rel))
    result = match_level(g, pts, np.zeros(3), 6)
    assert np.hypot(*(result.pose[:2] - true_rel[:2])) < 0.02
    assert abs(result.pose[2] - true_rel[2]) < 0.005
    assert result.residual < residual(g, pts, np.zeros(3))


def test_hessian_is_positive_definite_with_structure():
    g = level_with_first_scan()
    res = match_level(g, points_at(START), np.zeros(3), 2)
    assert np.all(np.linalg.eigvalsh(res.hessian) > 0)


def test_rotation_step_is_clamped():
    g = level_with_first_scan()
    pts = points_at(compose(START, np.array([0.0, 0.0, 1.0])))
    res = match_level(g, pts, np.zeros(3), 1, extension=1)
    assert abs(res.pose[2]) <= 0.2 + 1e-9


def test_rotation_search_finds_a_fast_turn():
    g = level_with_first_scan(0.1)
    pts = points_at(compose(START, np.array([0.0, 0.0, 0.12])))
    guess = best_rotation(g, pts, np.zeros(3), (-0.16, -0.08, 0.0, 0.08, 0.16))
    assert guess[2] == pytest.approx(0.16) or guess[2] == pytest.approx(0.08)


def test_empty_map_keeps_the_guess():
    g = GridLevel(100, 0.05, (-2.5, -2.5))
    res = match_level(g, points_at(START), np.array([0.1, 0.2, 0.3]), 6)
    assert res.pose == pytest.approx([0.1, 0.2, 0.3])


def test_transform_helpers_are_consistent():
    a = np.array([1.0, 2.0, 0.5])
    b = np.array([-0.3, 0.7, -1.2])
    assert compose(a, inverse(a)) == pytest.approx(np.zeros(3), abs=1e-12)
    p = np.array([[0.4, -0.2]])
    assert transform_points(compose(a, b), p) == pytest.approx(transform_points(a, transform_points(b, p)))


def test_batched_residuals_equal_single_ones():
    from hector_mapping.matcher import residuals
    g = level_with_first_scan()
    pts = points_at(START)
    cands = np.array([[0.0, 0.0, 0.0], [0.1, -0.05, 0.02], [-0.2, 0.1, -0.3]])
    assert residuals(g, pts, cands) == pytest.approx([residual(g, pts, c) for c in cands])
