"""Which circle is the hole to shoot: the one the depth camera sees through, else the middle one of three
circles in a row (a hole between decoys).

Pure functions on (x, y, z, radius) tuples, so that agents can use them on detections in the camera
optical frame (x right, y down, z forward) without importing OpenCV or ROS.
"""
from __future__ import annotations

import math
from itertools import combinations
from typing import Optional, Sequence, Tuple

from circle_detector import constants as C

CircleXYZR = Tuple[float, float, float, float]


def triple_score(triple: Sequence[CircleXYZR]) -> Optional[float]:
    """Cost (lower is better) of three circles being one holder, or None if they cannot be one.

    They must be in a horizontal row (sorted by x), of similar radius and depth, evenly spaced, and
    not too far apart for their size.
    """
    a, b, c = sorted(triple, key=lambda t: t[0])
    radii = [a[3], b[3], c[3]]
    if min(radii) <= 0 or max(radii) / min(radii) > C.TRIPLE_MAX_RADIUS_RATIO:
        return None
    g1 = ((b[0] - a[0]) ** 2 + (b[2] - a[2]) ** 2) ** 0.5
    g2 = ((c[0] - b[0]) ** 2 + (c[2] - b[2]) ** 2) ** 0.5
    if min(g1, g2) <= 0:
        return None
    spacing_ratio = max(g1, g2) / min(g1, g2)
    if spacing_ratio > C.TRIPLE_MAX_SPACING_RATIO:
        return None
    mean_r = sum(radii) / 3.0
    if max(g1, g2) / mean_r > C.TRIPLE_MAX_GAP_IN_RADII:
        return None
    extent = g1 + g2
    ys = [a[1], b[1], c[1]]
    slope = (max(ys) - min(ys)) / extent
    if slope > C.TRIPLE_MAX_VERTICAL_SLOPE:
        return None
    zs = [a[2], b[2], c[2]]
    if max(zs) - min(zs) > C.TRIPLE_MAX_DEPTH_SLOPE * abs(c[0] - a[0]):
        return None
    # collinearity in the facade: the middle one should sit between the others
    mid_y = (a[1] + c[1]) / 2.0
    mid_z = (a[2] + c[2]) / 2.0
    off = ((b[1] - mid_y) ** 2 + (b[2] - mid_z) ** 2) ** 0.5 / extent
    return (spacing_ratio - 1.0) + slope + off + (max(radii) / min(radii) - 1.0)


def choose_middle_hole(circles: Sequence[CircleXYZR]) -> Optional[int]:
    """Index in `circles` of the hole to shoot: the middle circle of the best-matching triple, or None.

    With fewer than three circles there is no safe choice (a decoy looks like the hole), so None.
    """
    best: Optional[Tuple[float, int]] = None
    idx = list(range(len(circles)))
    for combo in combinations(idx, 3):
        score = triple_score([circles[i] for i in combo])
        if score is None:
            continue
        middle = sorted(combo, key=lambda i: circles[i][0])[1]
        if best is None or score < best[0]:
            best = (score, middle)
    return None if best is None else best[1]


def is_opening(opening_m: float) -> bool:
    """A circle whose middle lies at least C.OPENING_MIN_DEPTH behind its rim: a hole, not a painted decoy."""
    return math.isfinite(opening_m) and opening_m >= C.OPENING_MIN_DEPTH


def is_painted(opening_m: float) -> bool:
    """A circle whose middle is known to lie on its rim's surface: a decoy (NaN: unknown, not painted)."""
    return math.isfinite(opening_m) and opening_m < C.OPENING_MIN_DEPTH


def choose_hole(circles: Sequence[CircleXYZR], openings: Optional[Sequence[float]] = None) -> Optional[int]:
    """Index in `circles` of the hole to shoot, or None when no choice is safe.

    `openings` (m, per circle, NaN unknown; see hough.Circle.opening_m) is the stronger evidence: the
    middle of a triple is taken unless it is known painted; with no usable triple, the single circle
    the depth camera sees through is taken (e.g. a holder at a building corner, where the decoy beyond
    the corner is out of sight). Without openings this is choose_middle_hole.
    """
    middle = choose_middle_hole(circles)
    if openings is None:
        return middle
    if len(openings) != len(circles):
        raise ValueError(f"{len(openings)} openings for {len(circles)} circles")
    open_ones = [i for i, o in enumerate(openings) if is_opening(o)]
    if middle is not None and not is_painted(openings[middle]):
        return middle
    return open_ones[0] if len(open_ones) == 1 else None
