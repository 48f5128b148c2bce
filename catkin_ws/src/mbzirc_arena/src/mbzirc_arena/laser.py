"""A laser scan's ranges as points (NumPy only, no ROS type): the one conversion every scan user shares.

Why in mbzirc_arena: the agents (leg and wall guards) and indoor_localization (the outline fit) both place a
LaserScan's returns in a plane; they differ only in what a range below the minimum means to them, which is a
parameter here, not a second copy.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np


def scan_points(ranges: Sequence[float], angle_min: float, angle_increment: float,
                pose: Sequence[float] = (0.0, 0.0, 0.0, 0.0), range_min: float = 0.0,
                range_max: float = math.inf, keep_near: bool = False) -> np.ndarray:
    """(N, 2) x, y of the scan's returns, the laser at pose (x, y, z, yaw) (default: the laser's own frame).

    Rules: NaN, +inf and ranges beyond range_max are no return. keep_near False (a map's use): ranges below
    range_min, -inf among them, are no return either. keep_near True (an obstacle guard's use, REP 117):
    -inf is a return at range_min and every range from 0 up counts: something is that close."""
    r = np.asarray(ranges, dtype=float)
    if keep_near:
        r = np.where(r == -math.inf, float(range_min), r)
    low = 0.0 if keep_near else range_min
    ok = np.isfinite(r) & (r >= low) & (r <= range_max)
    a = float(pose[3]) + float(angle_min) + float(angle_increment) * np.arange(r.size)
    r, a = r[ok], a[ok]
    return np.column_stack((pose[0] + r * np.cos(a), pose[1] + r * np.sin(a)))


__all__ = ['scan_points']
