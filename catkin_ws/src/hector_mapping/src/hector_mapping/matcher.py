"""Gauss-Newton scan matching against one grid level (Kohlbrecher et al. 2011, section IV-B).

Minimises sum_i (1 - M(S_i(xi)))^2 over the pose xi = (x, y, theta), where S_i(xi) is scan point i moved
by xi and M the bilinearly interpolated occupancy probability. Each step solves H dxi = J^T r with
J_i = grad M(S_i) . dS_i/dxi and H = J^T J.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .constants import ITERATION_EXTENSION, MAX_ROTATION_STEP, START_MARGIN, STEP_TOLERANCE
from .geometry import wrap_angle
from .grid import GridLevel


@dataclass
class MatchResult:
    """Outcome of matching one scan on one level.

    Attributes:
        pose: the estimated pose (x, y, theta).
        hessian: J^T J at the returned pose (world units), the information the scan carries.
        residual: mean of (1 - M)^2 over the points at the returned pose (lower = better fit).
        iterations: Gauss-Newton steps taken.
    """

    pose: np.ndarray
    hessian: np.ndarray
    residual: float
    iterations: int = 0


def _moved(pts: np.ndarray, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rotated points (rx, ry) and the points moved by ``pose`` (world)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    rx = c * pts[:, 0] - s * pts[:, 1]
    ry = s * pts[:, 0] + c * pts[:, 1]
    world = np.empty_like(pts)
    world[:, 0] = rx + pose[0]
    world[:, 1] = ry + pose[1]
    return rx, ry, world


def residual(level: GridLevel, pts: np.ndarray, pose: np.ndarray) -> float:
    """Mean of (1 - M)^2 over the scan points at ``pose``."""
    m, _, _ = level.interpolate(_moved(pts, pose)[2])
    r = 1.0 - m
    return float(np.dot(r, r)) / max(len(r), 1)


def residuals(level: GridLevel, pts: np.ndarray, poses: np.ndarray) -> np.ndarray:
    """Mean of (1 - M)^2 over the scan points for each of the candidate poses (C, 3), in one batch."""
    poses = np.asarray(poses, np.float64)
    c = np.cos(poses[:, 2])[:, None]
    s = np.sin(poses[:, 2])[:, None]
    wx = c * pts[None, :, 0] - s * pts[None, :, 1] + poses[:, 0:1]
    wy = s * pts[None, :, 0] + c * pts[None, :, 1] + poses[:, 1:2]
    m, _, _ = level.interpolate(np.stack((wx.reshape(-1), wy.reshape(-1)), axis=1))
    r = 1.0 - m.reshape(poses.shape[0], pts.shape[0])
    return np.mean(r * r, axis=1)


def _linearise(level: GridLevel, pts: np.ndarray, pose: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, float]:
    """H = J^T J, g = J^T r and the mean squared residual at ``pose``."""
    rx, ry, world = _moved(pts, pose)
    m, gx, gy = level.interpolate(world)
    r = 1.0 - m
    jac = np.empty((pts.shape[0], 3))
    jac[:, 0] = gx
    jac[:, 1] = gy
    jac[:, 2] = gy * rx - gx * ry          # grad M . d(world)/d(theta), d(world)/d(theta) = (-ry, rx)
    return jac.T @ jac, jac.T @ r, float(np.dot(r, r)) / max(len(r), 1)


def best_start(level: GridLevel, pts: np.ndarray, bases: Sequence[np.ndarray], offsets: Sequence[float],
               margin: float = START_MARGIN) -> np.ndarray:
    """Of each base pose turned by each rotation offset, the one whose residual is lowest.

    All candidates are scored in one batch. The first base unturned is kept unless another candidate
    is better by more than ``margin`` (relative): on a flat residual landscape (few, far points) a
    marginal winner is noise, and following it every scan would make the pose wander.
    """
    offs = sorted(offsets, key=abs)
    cands = np.array([[b[0], b[1], wrap_angle(b[2] + o)] for b in bases for o in offs])
    scores = residuals(level, pts, cands)
    best = int(np.argmin(scores))
    if scores[best] >= (1.0 - margin) * scores[0]:
        best = 0
    return cands[best].copy()


def best_rotation(level: GridLevel, pts: np.ndarray, pose: np.ndarray, offsets: Sequence[float]
                  ) -> np.ndarray:
    """``pose`` turned by the offset (from ``offsets``) whose residual is lowest."""
    return best_start(level, pts, [np.asarray(pose, np.float64)], offsets)


def match_level(level: GridLevel, pts: np.ndarray, pose: np.ndarray, iterations: int,
                extension: int = ITERATION_EXTENSION) -> MatchResult:
    """Refine ``pose`` so that the scan points ``pts`` (N, 2, in the robot frame) fit ``level``.

    Takes ``iterations`` Gauss-Newton steps, and more (up to ``extension`` times as many) while the step
    is still larger than STEP_TOLERANCE. The rotation of a step is clamped to +-MAX_ROTATION_STEP; a
    singular Hessian (no structure in view) stops the iteration and keeps the current pose.
    """
    pose = np.array(pose, dtype=np.float64)
    taken = 0
    for it in range(iterations * max(extension, 1)):
        h, g, _ = _linearise(level, pts, pose)
        if not np.all(np.isfinite(h)) or abs(np.linalg.det(h)) < 1e-12:
            break
        try:
            delta = np.linalg.solve(h, g)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(delta)):
            break
        delta[2] = min(max(delta[2], -MAX_ROTATION_STEP), MAX_ROTATION_STEP)
        pose += delta
        pose[2] = wrap_angle(pose[2])
        taken += 1
        if it + 1 >= iterations and np.max(np.abs(delta)) < STEP_TOLERANCE:
            break
    h, _, res = _linearise(level, pts, pose)
    return MatchResult(pose, h, res, taken)
