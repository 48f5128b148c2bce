"""Wall clearance indoors, measured by the robot's own laser: the standoff of a watering pose from the wall
it faces, and the least distance kept from every wall while the robot holds there.

Why: indoors a watering pose is placed on the fire's GNSS-frame estimate, and a robot flies to it and holds
it on its own GNSS fix; both carry errors of ~0.7 m that drift (realistic seeds 104 and 106: a UAV's
watering pose on floor 2 was truly ~0.7 m off the interior wall the fire is on, and while it held there its
GNSS error drifted towards the wall: it hit the wall). The laser measures the walls as they are.

Rules:
- the approach stops at `standoff` from the nearest wall return ahead along the approach's horizontal
  direction (the leg guard's corridor, leg_guard.corridor_distances), never nearer than its GNSS target:
  the laser only shortens the way (or backs out, when the robot already is nearer than the standoff);
- while holding, a robot whose nearest returns are nearer than `min_clearance` backs off away from them
  (from the mean of the returns within that distance) to `min_clearance + margin`: the margin is the
  hysteresis, so that a set-point is not re-sent for noise;
- at least leg_guard.MIN_BEAMS returns make a wall (one stray return moves nothing);
- without a trusted pose (pose source none: no GNSS fix, no valid localization) the same back-off is flown
  as a velocity (`away_velocity`): it needs the returns about the robot only, not where it is;
- a fire is watered square to the wall it burns on (`wall_normal_at`): the wall is the straight run of
  returns within NORMAL_RADIUS of its estimate (WALL_NORMAL_MIN_POINTS, spread over WALL_NORMAL_MIN_SPAN m,
  RMS under WALL_NORMAL_MAX_RMS: a corner is none), its normal the one on the robot's side.
Pure geometry here (no ROS); the task's use of it is in tasks/indoor.py.
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

import numpy as np

from .leg_guard import MIN_BEAMS, corridor_distances

NORMAL_RADIUS = 1.0            # m about a fire's estimate whose returns are its wall
WALL_NORMAL_MIN_POINTS = 8
WALL_NORMAL_MIN_SPAN = 0.8     # m
WALL_NORMAL_MAX_RMS = 0.08     # m: straighter than this is one wall (two walls of a corner are not)
WALL_NORMAL_MAX_OFF = 0.7      # m: the estimate lies no farther from the wall's line (else it is another wall)


def wall_ahead(points: np.ndarray, here: Sequence[float], direction: Sequence[float], half_width: float,
               reach: float) -> Optional[float]:
    """Distance ahead along the unit direction of the nearest wall return in the corridor of half_width,
    no farther than reach; None without a wall there."""
    ahead = np.sort(corridor_distances(points, here, direction, half_width, reach))
    return float(ahead[MIN_BEAMS - 1]) if ahead.size >= MIN_BEAMS else None


def stop_short(points: np.ndarray, here: Sequence[float], target: Sequence[float], half_width: float,
               standoff: float) -> Optional[np.ndarray]:
    """The x, y on the horizontal line from here to target that is `standoff` from the wall the laser sees
    ahead along it, when that is short of target; None when target already keeps the standoff (or no wall)."""
    d = np.asarray(target[:2], dtype=float) - np.asarray(here[:2], dtype=float)
    length = float(np.hypot(d[0], d[1]))
    if length < 1e-6:
        return None
    u = d / length
    wall = wall_ahead(points, here, u, half_width, length + standoff)
    if wall is None or wall - standoff >= length:
        return None
    return np.asarray(here[:2], dtype=float) + u * (wall - standoff)


def back_off(points: np.ndarray, here: Sequence[float], min_clearance: float,
             margin: float) -> Optional[np.ndarray]:
    """The horizontal offset (x, y) that moves a robot at here whose nearest wall returns are nearer than
    min_clearance away from them to min_clearance + margin; None when it keeps min_clearance."""
    if len(points) == 0:
        return None
    rel = np.asarray(points, dtype=float) - np.asarray(here[:2], dtype=float)
    dist = np.hypot(rel[:, 0], rel[:, 1])
    near = dist < min_clearance
    if np.count_nonzero(near) < MIN_BEAMS:
        return None
    towards = rel[near].mean(axis=0)
    norm = float(np.hypot(towards[0], towards[1]))
    if norm < 1e-6:
        return None
    nearest = float(np.sort(dist[near])[MIN_BEAMS - 1])
    return -towards / norm * (min_clearance + margin - nearest)


def off_the_walls(points: Optional[np.ndarray], here: Sequence[float], min_clearance: float,
                  margin: float) -> Optional[tuple]:
    """The (x, y, z) to hold instead of here (x, y, z, ...) when the walls in points are nearer than
    min_clearance (back_off); None when here keeps it, or without a scan."""
    if points is None:
        return None
    off = back_off(points, here, min_clearance, margin)
    if off is None:
        return None
    return (float(here[0] + off[0]), float(here[1] + off[1]), float(here[2]))


def away_velocity(points: Optional[np.ndarray], min_clearance: float, margin: float, gain: float,
                  speed: float) -> Optional[np.ndarray]:
    """Horizontal velocity (vx, vy) that moves a robot off walls nearer than min_clearance, from its laser
    returns relative to it (points: x, y about the robot, level, arena-aligned: no position needed): along
    back_off's offset, gain (1/s) times its length, at most speed; None when the walls keep min_clearance
    (or without a scan)."""
    if points is None:
        return None
    off = back_off(points, (0.0, 0.0), min_clearance, margin)
    if off is None:
        return None
    length = float(np.hypot(off[0], off[1]))
    return off / max(length, 1e-9) * min(speed, gain * length)


__all__ = ['away_velocity', 'back_off', 'off_the_walls', 'stop_short', 'wall_ahead']


def wall_normal_at(points: Optional[np.ndarray], fire: Sequence[float], here: Sequence[float]
                   ) -> Optional[np.ndarray]:
    """The unit normal (x, y) of the wall the laser sees at the fire's estimate, pointing to here's side;
    None without a fresh scan, or when the returns there are not one straight wall passing near the estimate.
    Why (the on-demand rostest indoor_gnss_denied, 3 runs of 3): a watering pose on the line from where the
    robot happened to be met the fire's wall at a grazing angle; the jet poured a whole tank beside the fire
    on that wall while the camera saw it hot."""
    if points is None or len(points) < WALL_NORMAL_MIN_POINTS:
        return None
    pts = np.asarray(points, dtype=float)[:, :2]
    f = np.asarray(fire[:2], dtype=float)
    near = pts[np.hypot(*(pts - f).T) <= NORMAL_RADIUS]
    if len(near) < WALL_NORMAL_MIN_POINTS:
        return None
    centre = near.mean(axis=0)
    _, sv, vt = np.linalg.svd(near - centre, full_matrices=False)
    direction, normal = vt[0], vt[1]
    along = (near - centre) @ direction
    rms = float(sv[1]) / math.sqrt(len(near))
    if np.ptp(along) < WALL_NORMAL_MIN_SPAN or rms > WALL_NORMAL_MAX_RMS \
            or abs(float((f - centre) @ normal)) > WALL_NORMAL_MAX_OFF:
        return None
    if float((np.asarray(here[:2], dtype=float) - centre) @ normal) < 0.0:
        normal = -normal
    return normal
