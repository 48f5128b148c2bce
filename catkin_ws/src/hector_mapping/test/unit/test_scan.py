"""Scan checks and conversion: malformed scans are rejected, bad returns dropped, z band applied."""
import math

import numpy as np
import pytest

from hector_mapping.geometry import rotation_matrix
from hector_mapping.scan import ScanFilter, check_scan, laser_to_base, scan_to_points

INC = 2 * math.pi / 720


def test_good_360_scan_passes_both_conventions():
    assert check_scan(720, -math.pi, math.pi - INC, INC) is None
    assert check_scan(720, -math.pi, math.pi, INC) is None


@pytest.mark.parametrize("n, amin, amax, inc", [
    (0, -math.pi, math.pi, INC),                 # empty
    (720, -math.pi, math.pi, 0.0),               # zero increment
    (720, -math.pi, math.pi, 2 * INC),           # wrong increment
    (720, -math.pi, math.pi, float("nan")),      # NaN increment
    (720, -math.pi, math.pi, -INC),              # negative count
])
def test_malformed_scans_are_rejected(n, amin, amax, inc):
    assert isinstance(check_scan(n, amin, amax, inc), str)


def test_bad_returns_are_dropped():
    r = np.array([1.0, np.nan, np.inf, 0.2, 31.0, 2.0, -1.0, 5.0])
    pts = scan_to_points(r, 0.0, 0.1, 0.15, 25.0, ScanFilter())
    assert len(pts) == 3                           # 1.0, 2.0, 5.0 (31 > laser_max, 0.2 < laser_min)
    assert np.hypot(pts[:, 0], pts[:, 1]) == pytest.approx([1.0, 2.0, 5.0])
    assert pts[1] == pytest.approx([2 * math.cos(0.5), 2 * math.sin(0.5)])
    assert len(scan_to_points(np.full(5, np.nan), 0.0, 0.1, 0.1, 10.0, ScanFilter())) == 0


def test_message_range_max_is_respected():
    pts = scan_to_points(np.array([5.0, 9.0]), 0.0, 0.1, 0.1, 8.0, ScanFilter())
    assert len(pts) == 1


def test_laser_to_base_applies_mount_and_z_band():
    # Laser upside down (roll pi) 0.2 m ahead, 0.1 m up: +y of the laser is -y of the base.
    rot = rotation_matrix(1.0, 0.0, 0.0, 0.0)
    pts, origin = laser_to_base(np.array([[1.0, 1.0]]), rot, np.array([0.2, 0.0, 0.1]), ScanFilter())
    assert pts[0] == pytest.approx([1.2, -1.0])
    assert origin == pytest.approx([0.2, 0.0])
    pts, _ = laser_to_base(np.array([[1.0, 1.0]]), np.eye(3), np.array([0.0, 0.0, 2.0]), ScanFilter())
    assert len(pts) == 0
