"""Gauss-Newton scan matching against one grid level (Kohlbrecher et al. 2011, section IV-B).

Minimises sum_i (1 - M(S_i(xi)))^2 over the pose xi = (x, y, theta), where S_i(xi) is scan point i moved
by xi and M the bilinearly interpolated occupancy probability. Each step solves H dxi = J^T r with
J_i = grad M(S_i) . dS_i/dxi and H = J^T J.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .constants import MAX_ROTATION_STEP
from .geometry import wrap_angle
from .grid import GridLevel


@dataclass
class MatchResult:
    """Outcome of matching one scan on one level.

    Attributes:
        pose: the estimated pose (x, y, theta).
        hessian: J^T J at the returned pose (world units), the information the scan carries.
        residual: mean of (1 - M)^2 over the points at the returned pose (lower = better fit).
    """

    pose: np.ndarray
    hessian: np.ndarray
    residual: float


def _linearise(level: GridLevel, pts: np.ndarray, pose: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, float]:
    """H = J^T J, g = J^T r and the mean squared residual at ``pose``."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    px, py = pts[:, 0], pts[:, 1]
    rx = c * px - s * py
    ry = s * px + c * py
    world = np.empty_like(pts)
    world[:, 0] = rx + pose[0]
    world[:, 1] = ry + pose[1]
    m, gx, gy = level.interpolate(world)
    r = 1.0 - m
    # d(world)/d(theta) = (-ry, rx)
    jac = np.empty((pts.shape[0], 3))
    jac[:, 0] = gx
    jac[:, 1] = gy
    jac[:, 2] = gy * rx - gx * ry
    return jac.T @ jac, jac.T @ r, float(np.dot(r, r)) / max(len(r), 1)


def match_level(level: GridLevel, pts: np.ndarray, pose: np.ndarray, iterations: int) -> MatchResult:
    """Refine ``pose`` so that the scan points ``pts`` (N, 2, in the robot frame) fit ``level``.

    The rotation of a step is clamped to +-MAX_ROTATION_STEP; a singular Hessian (no
    structure in view) stops the iteration and keeps the current pose.
    """
    pose = np.array(pose, dtype=np.float64)
    for _ in range(iterations):
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
    h, _, res = _linearise(level, pts, pose)
    return MatchResult(pose, h, res)
