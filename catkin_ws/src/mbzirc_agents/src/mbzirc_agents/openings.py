"""Find a window or door in the wall ahead from one 2D laser scan (pure: no ROS).

Why: the robots fly and drive on GNSS, a metre off; a straight leg through a 2 m window computed in the
arena frame hits the frame. The thesis detected the window before entering; the laser sees the opening as
it is, in the robot's own frame.

How: the wall is the nearest straight run of returns ahead, one stretch sideways (a line x = d + k y in
the body frame, fitted to the beams within +-`max_angle` of the heading); each beam is then *wall* (on the line, within
`wall_depth` behind it: the window's reveal in a thick wall counts), *through* (clearly beyond it, or no
return at all), *near* (something in front of the wall) or *unknown* (NaN, below the range minimum). An
opening is a run of through / unknown beams bounded by wall beams on BOTH sides (a building's corner, open
on one side, is none), with at least `min_through` through beams, whose width (between the hit points of
the bounding wall beams) is within `tolerance` of the expected one.
Body frame: x ahead, y left; beam angles counter-clockwise from x (a LaserScan of a laser mounted level,
looking ahead, as ual_sim's and the real robots' are).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

WALL, THROUGH, NEAR, UNKNOWN = 0, 1, 2, 3


@dataclass(frozen=True)
class SeenOpening:
    """An opening in the wall ahead, body frame.

    Args:
        lateral: m, body y of its centre (left +); distance: m, the wall's distance along x at the centre;
        width: m between its edges; left, right: body y of the left and right edges; at: arena (x, y) of its
        centre on the wall's face, placed with the pose the robot had when the scan was taken (the passage
        sets it; None from the finder, which knows no pose).
    """
    lateral: float
    distance: float
    width: float
    left: float
    right: float
    at: Optional[Tuple[float, float]] = None


def _one_stretch(y: np.ndarray, inl: np.ndarray, max_gap: float) -> np.ndarray:
    """inl reduced to its largest stretch along y with no gap wider than max_gap between neighbours."""
    idx = np.flatnonzero(inl)
    if idx.size < 2:
        return inl
    idx = idx[np.argsort(y[idx])]
    cuts = np.flatnonzero(np.diff(y[idx]) > max_gap) + 1
    best = max(np.split(idx, cuts), key=len)
    out = np.zeros_like(inl)
    out[best] = True
    return out


def _wall_line(x: np.ndarray, y: np.ndarray, band: float, min_beams: int, max_slope: float = 0.5,
               min_span: float = 1.0, max_gap: float = 3.0) -> Optional[Tuple[float, float]]:
    """(d, k) of the nearest wall x = d + k y facing the robot, or None: at least min_beams returns within
    +-band of the line, in one stretch sideways (no gap wider than max_gap, wider than any opening passed)
    spread over min_span m, at most max_slope off square (a side wall beside the robot, whose returns also
    crowd at a short x, is none).

    The nearest, not the largest: through a window the far side of the room may hold more beams. One
    stretch: near a room's corner the side walls' returns at the sector's ends lie at a short x too, metres
    apart sideways; taken with the wall's, they made a line of no wall (recorded inside views: the UGV
    just inside its door, a UAV 1.4 m aside of its window, its heading 7 deg off the wall's normal). The
    line is fitted again on the returns near the last fit, so that a wall seen at a slant is followed."""
    order = np.sort(x)
    if order.size < min_beams:
        return None
    counts = np.searchsorted(order, order + band, side='right') - np.searchsorted(order, order - band)
    tried = -np.inf
    for c in order[counts >= min_beams]:
        if c <= tried + band:
            continue
        tried = float(c)
        d, k, inl = float(c), 0.0, None
        for tol in (band, band, 0.5 * band):
            inl = _one_stretch(y, np.abs(x - (d + k * y)) <= tol, max_gap)
            if inl.sum() < min_beams:
                inl = None
                break
            d, k = _line_fit(x, y, inl)
        if inl is None:
            continue
        along = _along_the_line(x, y, inl)
        if along.sum() < inl.sum():                  # fitted again only without what ran across it
            inl = along
            if inl.sum() < min_beams:
                continue
            d, k = _line_fit(x, y, inl)
        if abs(k) <= max_slope and np.ptp(y[inl]) >= min_span:
            return float(d), float(k)
    return None


def _line_fit(x: np.ndarray, y: np.ndarray, inl: np.ndarray) -> Tuple[float, float]:
    """(d, k) of the least-squares line x = d + k y through the returns inl."""
    A = np.column_stack([np.ones(int(inl.sum())), y[inl]])
    (d, k), *_ = np.linalg.lstsq(A, x[inl], rcond=None)
    return float(d), float(k)


def _along_the_line(x: np.ndarray, y: np.ndarray, inl: np.ndarray, gap: float = 0.3) -> np.ndarray:
    """inl without the pieces of returns (split where neighbours sideways are more than `gap` apart: an
    opening) that spread across the line more than along it: a side wall seen end-on within the band, not
    the wall ahead. Why: in a corridor 2.7 m wide the two side walls' returns at the same short x made a
    "wall" across the corridor 0.4 m ahead with a 2.7 m "doorway" in it, which a UAV leaving floor 1 of
    another floor plan centred on for 16 s until it hit the end wall (c3_floor_plan_b, realistic seed 101 at
    rtf 4). Such returns still bound an opening in the wall the rest makes (labels go by the line)."""
    idx = np.flatnonzero(inl)
    idx = idx[np.argsort(y[idx])]
    out = inl.copy()
    for piece in np.split(idx, np.flatnonzero(np.diff(y[idx]) > gap) + 1):
        if piece.size >= 3 and np.ptp(y[piece]) < np.ptp(x[piece]):
            out[piece] = False
    return out


def classify_beams(ranges: Sequence[float], angle_min: float, angle_increment: float,
                   range_min: float = 0.0, range_max: float = math.inf, max_angle: float = math.radians(80),
                   wall_depth: float = 0.4, band: float = 0.15, min_wall_beams: int = 20
                   ) -> Optional[Tuple[np.ndarray, np.ndarray, np.ndarray, float, float]]:
    """(labels, lateral hit y, angles) of the beams ahead in angle order, and the wall (d, k); None when
    the scan is unusable or no wall is seen ahead."""
    if not math.isfinite(angle_min) or not math.isfinite(angle_increment) or angle_increment <= 0:
        return None
    r = np.asarray(ranges, dtype=float)
    if r.size == 0:
        return None
    a = angle_min + angle_increment * np.arange(r.size)
    a = np.arctan2(np.sin(a), np.cos(a))
    ahead = np.flatnonzero(np.abs(a) <= max_angle)
    ahead = ahead[np.argsort(a[ahead])]
    r, a = r[ahead], a[ahead]
    valid = np.isfinite(r) & (r > max(range_min, 0.0)) & (r < range_max)
    no_return = (r == np.inf) | (np.isfinite(r) & (r >= range_max))
    with np.errstate(invalid='ignore'):
        x, y = r * np.cos(a), r * np.sin(a)
    line = _wall_line(x[valid], y[valid], band, min_wall_beams)
    if line is None:
        return None
    d, k = line
    if d <= 0:
        return None
    labels = np.full(r.size, UNKNOWN)
    res = np.where(valid, x - (d + k * np.where(valid, y, 0.0)), 0.0)
    labels[valid & (np.abs(res) <= wall_depth)] = WALL
    labels[valid & (res > wall_depth)] = THROUGH
    labels[valid & (res < -wall_depth)] = NEAR
    labels[no_return] = THROUGH
    return labels, np.where(valid, y, np.nan), a, d, k


def find_openings(ranges: Sequence[float], angle_min: float, angle_increment: float, width: float,
                  tolerance: float = 0.4, range_min: float = 0.0, range_max: float = math.inf,
                  max_angle: float = math.radians(80), wall_depth: float = 0.4,
                  min_through: int = 3) -> List[SeenOpening]:
    """Every opening of plausible width (width +- tolerance) in the wall ahead, right to left.

    Robust to NaN / inf dropouts (an isolated no-return beam in the wall makes a gap far too narrow) and
    to range noise of a few centimetres (the wall band and `wall_depth`).
    """
    seen = classify_beams(ranges, angle_min, angle_increment, range_min, range_max, max_angle, wall_depth)
    if seen is None:
        return []
    labels, y, _a, d, k = seen
    out = []
    n = labels.size
    i = 0
    while i < n:
        if labels[i] in (WALL, NEAR):
            i += 1
            continue
        j = i
        while j < n and labels[j] in (THROUGH, UNKNOWN):
            j += 1
        # run [i, j): bounded by wall beams on both sides, never by the sector's ends or an obstacle
        if i > 0 and j < n and labels[i - 1] == WALL and labels[j] == WALL \
                and int(np.sum(labels[i:j] == THROUGH)) >= min_through:
            right, left = float(y[i - 1]), float(y[j])
            w = left - right
            if abs(w - width) <= tolerance:
                c = 0.5 * (left + right)
                out.append(SeenOpening(lateral=c, distance=d + k * c, width=w, left=left, right=right))
        i = j
    return out


def find_opening(ranges: Sequence[float], angle_min: float, angle_increment: float, width: float,
                 expected_lateral: float = 0.0, **kwargs) -> Optional[SeenOpening]:
    """The opening of plausible width nearest `expected_lateral` (m, body y), or None (see find_openings)."""
    found = find_openings(ranges, angle_min, angle_increment, width, **kwargs)
    if not found:
        return None
    return min(found, key=lambda o: abs(o.lateral - expected_lateral))


def side_clearances(ranges: Sequence[float], angle_min: float, angle_increment: float,
                    range_min: float = 0.0, half_sector: float = math.radians(30)) -> Tuple[float, float]:
    """(left, right): the lateral distance (|r sin a|) of the nearest valid return within +-half_sector of
    90 deg left and right (inf when none). Inside the opening, where its edges are beside the robot and
    find_openings no longer sees them ahead, the difference says how far off its middle the robot is."""
    if not math.isfinite(angle_min) or not math.isfinite(angle_increment) or angle_increment <= 0:
        return math.inf, math.inf
    r = np.asarray(ranges, dtype=float)
    a = angle_min + angle_increment * np.arange(r.size)
    a = np.arctan2(np.sin(a), np.cos(a))
    valid = np.isfinite(r) & (r > max(range_min, 0.0))
    with np.errstate(invalid='ignore'):
        lat = np.abs(r * np.sin(a))
    out = []
    for side in (1.0, -1.0):
        sel = valid & (np.abs(a - side * math.pi / 2) <= half_sector)
        out.append(float(lat[sel].min()) if sel.any() else math.inf)
    return out[0], out[1]
