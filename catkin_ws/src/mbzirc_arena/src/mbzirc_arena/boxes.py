"""Axis-aligned 3D boxes of airspace: what an agent reserves and what the region manager compares.

Why shared: the agent that builds a box and the manager that grants it must agree on what "overlap" means,
or two UAVs get the same airspace.
"""
from __future__ import annotations

import math
from typing import Iterable, Optional, Sequence

import numpy as np

Box = tuple  # (np.ndarray min xyz, np.ndarray max xyz)


def make_box(min_corner: Sequence[float], max_corner: Sequence[float]) -> Box:
    """A box from two corners given in any order (each axis is sorted)."""
    a = np.asarray(min_corner, dtype=float)
    b = np.asarray(max_corner, dtype=float)
    return np.minimum(a, b), np.maximum(a, b)


def boxes_overlap(a: Box, b: Box) -> bool:
    """True when the boxes share volume; boxes that only touch on a face do not overlap."""
    return bool(np.all(a[0] < b[1]) and np.all(b[0] < a[1]))


def swept_box(p0: Sequence[float], p1: Sequence[float], margin: float) -> Box:
    """The box covering the straight flight p0 -> p1, grown by margin on every side."""
    lo, hi = make_box(p0, p1)
    return lo - margin, hi + margin


def column_box(x: float, y: float, z0: float, z1: float, half_side: float) -> Box:
    """A vertical column over (x, y) between z0 and z1: take-off / landing airspace."""
    return make_box((x - half_side, y - half_side, min(z0, z1)), (x + half_side, y + half_side, max(z0, z1)))


def box_text(box: Box) -> str:
    """A box in words for the logs: [x, y, z .. x, y, z] to the decimetre (the agent and the manager
    name the same box the same way)."""
    return '[' + ', '.join(f'{v:.1f}' for v in box[0]) + ' .. ' + ', '.join(f'{v:.1f}' for v in box[1]) + ']'


def point_in_box(p: Sequence[float], box: Box) -> bool:
    """True when p is inside the box (faces included)."""
    q = np.asarray(p, dtype=float)
    return bool(np.all(q >= box[0]) and np.all(q <= box[1]))


def all_finite(values: Iterable[float]) -> bool:
    """True when no value is NaN or infinite."""
    return all(math.isfinite(v) for v in values)


def check_point(p: Sequence[float], arena: Sequence[float], what: str = 'waypoint') -> Optional[str]:
    """None when p is finite and inside the arena box (x0, y0, z0, x1, y1, z1), else the reason."""
    if not all_finite(p):
        return f'{what} has NaN or infinite coordinates: {tuple(p)}'
    box = make_box(arena[:3], arena[3:])
    if not point_in_box(p, box):
        return (f'{what} ({p[0]:.2f}, {p[1]:.2f}, {p[2]:.2f}) is outside the arena '
                f'{tuple(round(v, 2) for v in arena)}')
    return None
