"""Test fixture: simulated indoor flights on the first floor of ual_sim's tower, for the benchmark and the
test bag (not part of the SLAM, not installed).

Scans come from ual_sim's pure world model (``ual_sim.world.World.laser_scan``, the simulator's own 2D ray
caster on the C3 world file; ual_sim is a test dependency) when it is importable, i.e. in a sourced
workspace; otherwise from the stand-in floor plan ``sim2d.tower_floor``. :func:`world_source` says which.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

import sim2d

#: Flight height of the UAV on the tower's first floor (floor at 5.0 m; doorways up to 7.2 m, so a UAV of
#: 0.5 m radius passes under their lintel) and the laser mount above base_link (ual_sim's offset).
FLIGHT_Z = 6.2
LASER_Z_OFFSET = 0.1

#: A loop through the three rooms of the first floor of ual_sim's default world (east room, doorway at
#: y 10-12 in the wall x = 17.7, south-west room, doorway at x 13.5-15.5 in the wall y = 15, north-west
#: room), 0.6 m or more from every wall.
FLOOR1_LOOP = [(21.0, 9.0), (22.8, 13.0), (21.0, 17.8), (19.2, 14.0), (19.2, 11.0), (16.5, 11.0),
               (13.0, 9.0), (12.6, 13.5), (14.5, 13.5), (14.5, 17.5), (12.8, 18.2), (16.6, 17.8),
               (14.5, 16.5), (14.5, 13.5), (16.5, 11.0), (19.2, 11.0), (21.0, 9.0)]


@dataclass
class IndoorWorld:
    """A laser ray caster ``scan(x, y, yaw) -> ranges (720,)``, the walls at laser height as segments
    (M, 4) in the arena frame, the flight loop, and where it all comes from."""

    scan: Callable[[float, float, float], np.ndarray]
    source: str
    loop: list
    segments: np.ndarray


def _import_ual_sim():
    """ual_sim.world (the simulator's world model, a test dependency); None when not importable."""
    try:
        import ual_sim.world as world  # noqa: PLC0415 - optional: the stand-in floor plan otherwise
        return world
    except ImportError:
        return None


def world_source(prefer_ual_sim: bool = True) -> IndoorWorld:
    """The first floor of ual_sim's default world, or the stand-in floor plan if ual_sim is missing."""
    mod = _import_ual_sim() if prefer_ual_sim else None
    if mod is not None:
        w = mod.load_world()
        z = FLIGHT_Z + LASER_Z_OFFSET
        sel = (w.bmin[:, 2] <= z) & (z <= w.bmax[:, 2])
        segs = []
        for (x0, y0), (x1, y1) in zip(w.bmin[sel, :2], w.bmax[sel, :2]):
            segs += [(x0, y0, x1, y0), (x1, y0, x1, y1), (x1, y1, x0, y1), (x0, y1, x0, y0)]
        return IndoorWorld(lambda x, y, yaw: w.laser_scan(x, y, z, yaw),
                           "ual_sim.world (c3_default.yaml, tower first floor, laser at z 6.3 m)",
                           FLOOR1_LOOP, np.array(segs, np.float64))
    seg = sim2d.tower_floor()
    return IndoorWorld(lambda x, y, yaw: seg.raycast(x, y, yaw),
                       "hector_mapping.sim2d.tower_floor (stand-in, ual_sim not importable)",
                       sim2d.TOWER_LOOP, seg.segments)


def slow_flight(world: IndoorWorld, rate: float = 15.0) -> sim2d.Flight:
    """0.3 m/s, turning on the spot at 0.5 rad/s to face each leg."""
    return sim2d.fly(world.loop, speed=0.3, yaw_rate=0.5, rate=rate, spin=False)


def fast_turning_flight(world: IndoorWorld, rate: float = 15.0, start_yaw: float = 0.0) -> sim2d.Flight:
    """1 m/s while turning continuously at the UAV's 1 rad/s yaw limit."""
    return sim2d.fly(world.loop, speed=1.0, yaw_rate=1.0, rate=rate, spin=True, start_yaw=start_yaw)


def scans_along(world: IndoorWorld, flight: sim2d.Flight, noise: float, seed: int) -> np.ndarray:
    """Ranges (K, 720) along the flight with Gaussian range noise (ual_sim's laser is noise-free)."""
    rng = np.random.default_rng(seed)
    out = np.empty((len(flight.poses), sim2d.N_BEAMS), np.float32)
    for k, (x, y, yaw) in enumerate(flight.poses):
        r = np.asarray(world.scan(float(x), float(y), float(yaw)), np.float64)
        out[k] = r + rng.normal(0.0, noise, r.shape) if noise > 0.0 else r
    return out


def ate(estimates: np.ndarray, truth: np.ndarray) -> dict:
    """Trajectory errors of estimated (K, 3) map-frame poses against ground-truth (K, 3) poses.

    Returns ``ate_rms`` / ``ate_max``: absolute trajectory error after the least-squares rigid (SE(2))
    alignment of the two position tracks (the usual ATE); and ``start_aligned_rms`` /
    ``start_aligned_max``: errors when the map frame is simply put at the true start pose (stricter: it
    also counts a constant offset of the first map).
    """
    est = np.asarray(estimates, np.float64)
    gt = np.asarray(truth, np.float64)
    c0, s0 = math.cos(gt[0, 2]), math.sin(gt[0, 2])
    start = np.stack([gt[0, 0] + c0 * est[:, 0] - s0 * est[:, 1],
                      gt[0, 1] + s0 * est[:, 0] + c0 * est[:, 1]], axis=1)
    d0 = np.linalg.norm(start - gt[:, :2], axis=1)
    # Horn / Umeyama in 2D without scale.
    a, b = est[:, :2], gt[:, :2]
    ma, mb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((a - ma).T @ (b - mb))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rot = vt.T @ np.diag([1.0, d]) @ u.T
    aligned = (a - ma) @ rot.T + mb
    d1 = np.linalg.norm(aligned - b, axis=1)
    return {"ate_rms": float(np.sqrt(np.mean(d1 ** 2))), "ate_max": float(d1.max()),
            "start_aligned_rms": float(np.sqrt(np.mean(d0 ** 2))), "start_aligned_max": float(d0.max())}


def distance_to_segments(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Distance (N,) from each point (N, 2) to the nearest segment (M, 4: x0, y0, x1, y1)."""
    p = np.asarray(points, np.float64)[:, None, :]
    a = segments[None, :, :2]
    ab = segments[None, :, 2:] - a
    t = np.clip(np.sum((p - a) * ab, axis=2) / np.maximum(np.sum(ab * ab, axis=2), 1e-12), 0.0, 1.0)
    d = p - (a + t[..., None] * ab)
    return np.sqrt(np.min(np.sum(d * d, axis=2), axis=1))


def map_wall_check(occupied_xy: np.ndarray, seen_wall_xy: np.ndarray, segments: np.ndarray,
                   resolution: float) -> dict:
    """How well the occupied cells of a map (centres, arena frame) match the world's walls.

    Returns ``on_wall``: fraction of occupied cells whose centre is within one cell of a wall surface
    (``resolution`` plus half a cell diagonal, since a wall surface anywhere inside a cell makes that
    cell occupied); ``p99_distance`` / ``max_distance`` of occupied cells to the walls (m); and
    ``coverage``: fraction of wall points seen by the laser with an occupied cell within one cell.
    """
    d = distance_to_segments(occupied_xy, segments)
    tol = resolution * (1.0 + math.sqrt(0.5))
    near = np.zeros(len(seen_wall_xy), bool)
    if len(occupied_xy) and len(seen_wall_xy):
        from scipy.spatial import cKDTree  # noqa: PLC0415 - only the checks need scipy
        dist, _ = cKDTree(occupied_xy).query(seen_wall_xy, p=np.inf)
        near = dist <= 1.5 * resolution
    return {"on_wall": float(np.mean(d <= tol)) if len(d) else 0.0,
            "p99_distance": float(np.percentile(d, 99)) if len(d) else math.inf,
            "max_distance": float(d.max()) if len(d) else math.inf,
            "coverage": float(np.mean(near)) if len(near) else 0.0}
