"""A tiny 2D world of wall segments, a vectorised laser ray caster and kinematic indoor flights.

Used by the unit tests and as the benchmark's fallback when ual_sim's world model is not importable; it
is not part of the SLAM. The default floor plan is a 12.8 m x 12.8 m tower floor (arena frame, tower
footprint x 11.4-24.2, y 6.7-19.5) with window gaps and interior walls.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hector_mapping.geometry import wrap_angle

#: The RPLidar of the thesis: 720 beams over 360 degrees, first beam at -pi, front beam at index 360.
N_BEAMS = 720
ANGLE_MIN = -math.pi
ANGLE_INCREMENT = 2.0 * math.pi / N_BEAMS
RANGE_MIN = 0.15
RANGE_MAX = 25.0


@dataclass
class SegmentWorld:
    """Walls as segments (M, 4): x0, y0, x1, y1 (metres)."""

    segments: np.ndarray

    def raycast(self, x: float, y: float, yaw: float, n_beams: int = N_BEAMS,
                angle_min: float = ANGLE_MIN, angle_increment: float = ANGLE_INCREMENT,
                max_range: float = RANGE_MAX) -> np.ndarray:
        """Ranges (n_beams,) from (x, y) at heading ``yaw``; inf where no wall is within ``max_range``."""
        ang = yaw + angle_min + angle_increment * np.arange(n_beams)
        dx = np.cos(ang)[:, None]
        dy = np.sin(ang)[:, None]
        s = self.segments
        ex = (s[:, 2] - s[:, 0])[None, :]
        ey = (s[:, 3] - s[:, 1])[None, :]
        wx = (s[:, 0] - x)[None, :]
        wy = (s[:, 1] - y)[None, :]
        den = dx * ey - dy * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (wx * ey - wy * ex) / den
            u = (wx * dy - wy * dx) / den
        hit = (np.abs(den) > 1e-12) & (t > 0.0) & (u >= 0.0) & (u <= 1.0)
        t = np.where(hit, t, np.inf).min(axis=1)
        t[t > max_range] = np.inf
        return t


def _box(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float, float, float]]:
    return [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]


def tower_floor() -> SegmentWorld:
    """One floor of the tower: outer walls with 2 m window gaps, interior walls and a pillar."""
    x0, y0, x1, y1 = 11.4, 6.7, 24.2, 19.5
    segs = [
        # south wall (y0) with a window at x 16-18
        (x0, y0, 16.0, y0), (18.0, y0, x1, y0),
        # east wall (x1) with a window at y 12-14
        (x1, y0, x1, 12.0), (x1, 14.0, x1, y1),
        # north wall (y1) with a window at x 19-21
        (x1, y1, 21.0, y1), (19.0, y1, x0, y1),
        # west wall (x0), solid
        (x0, y1, x0, y0),
        # interior: a wall from the west with a door gap, a short wall from the north, an L
        (x0, 13.0, 14.5, 13.0), (15.7, 13.0, 17.0, 13.0),
        (18.5, y1, 18.5, 16.5),
        (20.5, 9.0, 20.5, 11.5), (20.5, 9.0, 22.5, 9.0),
    ]
    segs += _box(16.6, 9.4, 17.2, 10.0)          # a pillar
    segs += _box(21.6, 15.8, 22.4, 16.6)         # another pillar
    return SegmentWorld(np.array(segs, dtype=np.float64))


@dataclass
class Flight:
    """A flown trajectory sampled at the scan rate.

    Attributes:
        t: times (s), (K,).
        poses: ground-truth (x, y, yaw) per scan, (K, 3).
    """

    t: np.ndarray
    poses: np.ndarray


def fly(waypoints: list[tuple[float, float]], speed: float, yaw_rate: float, rate: float,
        spin: bool, start_yaw: float = 0.0) -> Flight:
    """Kinematic flight through ``waypoints`` sampled at ``rate`` Hz.

    With ``spin`` the UAV turns continuously at ``yaw_rate`` while it moves at ``speed`` (the hardest
    case for a matcher without odometry); otherwise it stops at each waypoint, turns to face the next
    leg at ``yaw_rate`` and flies it facing forward.
    """
    dt = 1.0 / rate
    pos = np.array(waypoints[0], dtype=np.float64)
    yaw = start_yaw
    out = [(pos[0], pos[1], yaw)]
    for wp in waypoints[1:]:
        target = np.array(wp, dtype=np.float64)
        heading = math.atan2(target[1] - pos[1], target[0] - pos[0])
        if not spin:
            while abs(wrap_angle(heading - yaw)) > 1e-9:
                d = wrap_angle(heading - yaw)
                yaw = wrap_angle(yaw + max(-yaw_rate * dt, min(yaw_rate * dt, d)))
                out.append((pos[0], pos[1], yaw))
        while np.linalg.norm(target - pos) > 1e-9:
            step = target - pos
            dist = np.linalg.norm(step)
            pos = target.copy() if dist <= speed * dt else pos + step / dist * speed * dt
            if spin:
                yaw = wrap_angle(yaw + yaw_rate * dt)
            out.append((pos[0], pos[1], yaw))
    poses = np.array(out)
    return Flight(np.arange(len(poses)) * dt, poses)


#: A loop through the rooms of tower_floor() that keeps 0.6 m from every wall.
TOWER_LOOP = [(13.0, 8.2), (15.1, 11.0), (18.8, 11.8), (19.0, 8.0), (23.3, 7.8), (23.3, 13.0),
              (20.0, 14.5), (19.7, 18.5), (19.5, 15.5), (16.5, 15.5), (13.0, 17.8), (15.1, 14.5),
              (15.1, 11.5), (13.0, 8.2)]


def slow_flight(rate: float = 15.0) -> Flight:
    """The slow indoor flight: 0.3 m/s, turning on the spot at 0.5 rad/s to face each leg."""
    return fly(TOWER_LOOP, speed=0.3, yaw_rate=0.5, rate=rate, spin=False)


def fast_turning_flight(rate: float = 15.0) -> Flight:
    """The hard flight: 1 m/s while turning continuously at the UAV's 1 rad/s yaw limit."""
    return fly(TOWER_LOOP, speed=1.0, yaw_rate=1.0, rate=rate, spin=True)


def simulate_scans(world: SegmentWorld, flight: Flight, noise: float, seed: int) -> np.ndarray:
    """Ranges (K, N_BEAMS) along a flight with Gaussian range noise of ``noise`` metres."""
    rng = np.random.default_rng(seed)
    scans = np.empty((len(flight.poses), N_BEAMS), np.float32)
    for k, (x, y, yaw) in enumerate(flight.poses):
        r = world.raycast(x, y, yaw)
        scans[k] = r + rng.normal(0.0, noise, r.shape) if noise > 0 else r
    return scans
