"""laser.scan_points: which ranges are returns (map use vs guard use, REP 117) and where they land."""
import math

import numpy as np
import pytest

from mbzirc_arena.laser import scan_points

RANGES = [np.nan, np.inf, -np.inf, 0.01, 2.0, 50.0]
ANGLE_MIN, INC = -math.pi, 0.5


def at(r, i):
    a = ANGLE_MIN + INC * i
    return r * math.cos(a), r * math.sin(a)


def test_a_map_keeps_only_ranges_within_the_limits():
    pts = scan_points(RANGES, ANGLE_MIN, INC, range_min=0.05, range_max=40.0)
    assert pts.shape == (1, 2) and pts[0] == pytest.approx(at(2.0, 4))


def test_a_guard_counts_too_close_returns_rep_117():
    pts = scan_points(RANGES, ANGLE_MIN, INC, range_min=0.05, range_max=40.0, keep_near=True)
    assert pts.shape == (3, 2)
    assert pts == pytest.approx(np.array([at(0.05, 2), at(0.01, 3), at(2.0, 4)]))


def test_the_points_are_placed_with_the_pose():
    pose = (3.0, -1.0, 2.0, math.pi / 2)
    pts = scan_points([1.0, 2.0], 0.0, math.pi / 2, pose)      # the beams point north and west
    assert pts == pytest.approx(np.array([(3.0, 0.0), (1.0, -1.0)]))


def test_no_beam_gives_no_point():
    assert scan_points([], 0.0, 0.1).shape == (0, 2)
    assert scan_points([np.nan] * 5, 0.0, 0.1, keep_near=True).shape == (0, 2)
