"""LaserScan arrays -> 2D points in the robot frame, with the checks that reject malformed scans (no ROS)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .constants import ANGLE_COUNT_TOLERANCE, MIN_SCAN_POINTS


@dataclass
class ScanFilter:
    """Range and height limits (the node's ``laser_min_dist``, ``laser_max_dist``, ``laser_z_*_value``)."""

    laser_min_dist: float = 0.4
    laser_max_dist: float = 30.0
    laser_z_min_value: float = -1.0
    laser_z_max_value: float = 1.0


def check_scan(n_ranges: int, angle_min: float, angle_max: float, angle_increment: float
               ) -> Optional[str]:
    """Why the scan's geometry is malformed, or None when it is usable."""
    if n_ranges == 0:
        return "empty scan (no ranges)"
    values = (angle_min, angle_max, angle_increment)
    if not all(math.isfinite(v) for v in values):
        return f"non-finite angles (min {angle_min}, max {angle_max}, increment {angle_increment})"
    if angle_increment == 0.0:
        return "angle_increment is 0"
    expected = (angle_max - angle_min) / angle_increment + 1.0
    if expected < 1.0 or abs(round(expected) - n_ranges) > ANGLE_COUNT_TOLERANCE:
        return (f"{n_ranges} ranges do not fit angle_min {angle_min:.4f}, angle_max {angle_max:.4f}, "
                f"angle_increment {angle_increment:.6f} (expected about {expected:.1f})")
    return None


def scan_to_points(ranges: np.ndarray, angle_min: float, angle_increment: float,
                   range_min: float, range_max: float, flt: ScanFilter) -> np.ndarray:
    """Valid returns as (N, 2) points in the laser frame.

    NaN, inf, returns outside the message's [range_min, range_max] and outside the filter's
    [laser_min_dist, laser_max_dist] are dropped.
    """
    r = np.asarray(ranges, np.float64)
    angles = angle_min + angle_increment * np.arange(r.shape[0])
    lo = max(flt.laser_min_dist, range_min if math.isfinite(range_min) else 0.0)
    hi = flt.laser_max_dist
    if math.isfinite(range_max) and range_max > 0.0:
        hi = min(hi, range_max)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(r) & (r >= lo) & (r <= hi)
    r = r[ok]
    a = angles[ok]
    return np.stack((r * np.cos(a), r * np.sin(a)), axis=1)


def laser_to_base(points: np.ndarray, rotation: np.ndarray, translation: np.ndarray, flt: ScanFilter
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Laser-frame points -> base-frame (x, y), keeping those with base z in the filter's band.

    Returns the points (N, 2) and the laser origin (2,) in the base frame.
    """
    p3 = np.zeros((points.shape[0], 3))
    p3[:, :2] = points
    base = p3 @ np.asarray(rotation).T + np.asarray(translation)
    keep = (base[:, 2] >= flt.laser_z_min_value) & (base[:, 2] <= flt.laser_z_max_value)
    return base[keep, :2], np.asarray(translation, np.float64)[:2].copy()


def enough_points(points: np.ndarray) -> bool:
    """Whether a scan has enough points to be matched."""
    return points.shape[0] >= MIN_SCAN_POINTS
