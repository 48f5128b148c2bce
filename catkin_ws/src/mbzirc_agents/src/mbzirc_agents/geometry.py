"""Geometry of the agents' tasks: facade standoff poses, facing poses, walls ahead, search paths.

Why pure: goal validation and path planning decide whether a UAV can meet a wall; they must be testable
without ROS. Boxes, yaw, footprint rules and 2D routing are the arena's (mbzirc_arena): the agents, the
region manager, the estimator and the central unit decide with the same code.
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np
from mbzirc_arena.buildings import facade_standoff  # noqa: F401  (the facade rule is the arena's)


def facing_pose(target: Sequence[float], frm: Sequence[float], distance: float) -> tuple:
    """((x, y, z), yaw) `distance` m from target on the side of `frm`, facing target (indoor fires)."""
    dx, dy = frm[0] - target[0], frm[1] - target[1]
    n = math.hypot(dx, dy)
    if n < 1e-6:
        dx, dy, n = 1.0, 0.0, 1.0
    pos = (target[0] + dx / n * distance, target[1] + dy / n * distance, frm[2])
    return pos, math.atan2(-dy, -dx)


def faces_wall(pos: Sequence[float], yaw: Optional[float], buildings: Sequence[Sequence[float]],
               max_dist: float = 3.5) -> bool:
    """True when a building wall is straight ahead of pos (heading yaw) within max_dist, at pos's height."""
    if yaw is None:
        return False
    for d in np.arange(0.1, max_dist + 1e-9, 0.1):
        q = (pos[0] + d * math.cos(yaw), pos[1] + d * math.sin(yaw))
        if any(b[0] <= q[0] <= b[2] and b[1] <= q[1] <= b[3] and pos[2] <= b[4] for b in buildings):
            return True
    return False


# ---- paths -------------------------------------------------------------------------------------------
def lawnmower(area: Sequence[float], spacing: float, z: float) -> list:
    """Boustrophedon waypoints [(x, y, z)] covering area (x_min, y_min, x_max, y_max), legs along x."""
    x0, y0, x1, y1 = area
    if spacing <= 0:
        raise ValueError('spacing must be > 0')
    n = max(1, int(math.ceil((y1 - y0) / spacing)) + 1)
    ys = np.linspace(y0, y1, n) if n > 1 else [0.5 * (y0 + y1)]
    pts = []
    for i, y in enumerate(ys):
        xs = (x0, x1) if i % 2 == 0 else (x1, x0)
        pts += [(float(xs[0]), float(y), z), (float(xs[1]), float(y), z)]
    return pts
