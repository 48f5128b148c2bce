"""The SLAM processor: multi-resolution maps, coarse-to-fine matching, update thresholds (no ROS).

Level i has cells of ``resolution * 2**i`` and ``size / 2**i`` cells per side; all levels cover the same
square and are updated with the same pose, so the coarse levels give the matcher a wide basin of
convergence and the finest one its accuracy.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from .constants import (COVARIANCE_FLOOR, ITERATION_EXTENSION, ITERATIONS_COARSE, ITERATIONS_FINE,
                        MIN_SCAN_POINTS, RECOVERY_CANDIDATES, RECOVERY_FACTOR, RECOVERY_MIN_RESIDUAL,
                        RECOVERY_ROTATIONS, RECOVERY_TRANSLATIONS, RESIDUAL_AVERAGE_WEIGHT,
                        ROTATION_SEARCH_OFFSETS)
from .geometry import transform_points, wrap_angle
from .grid import GridLevel
from .matcher import MatchResult, best_start, match_level, residuals


@dataclass
class SlamParams:
    """Map and update parameters (the node's ``~`` parameters of the same names)."""

    map_resolution: float = 0.025
    map_size: int = 1024
    map_start_x: float = 0.5
    map_start_y: float = 0.5
    map_multi_res_levels: int = 3
    update_factor_free: float = 0.4
    update_factor_occupied: float = 0.9
    map_update_distance_thresh: float = 0.4
    map_update_angle_thresh: float = 0.9
    #: Start each match from a constant-velocity prediction of the pose (from the last two estimates)
    #: instead of the last pose. Not in the original; it keeps the match inside the basin of convergence
    #: when the robot turns fast at a low scan rate.
    use_motion_prediction: bool = True
    #: Try a few rotations around the guess on the coarsest level before Gauss-Newton (not in the
    #: original; see constants.ROTATION_SEARCH_OFFSETS).
    rotation_search: bool = True
    #: Keep iterating (up to constants.ITERATION_EXTENSION times the nominal count) while the steps are
    #: still large; False gives the original's fixed iteration counts.
    iterate_to_convergence: bool = True
    #: Search a wider set of starting poses when a match fits much worse than the recent ones (not in
    #: the original; see constants.RECOVERY_*).
    recovery_search: bool = True


@dataclass
class SlamStep:
    """Result of processing one scan.

    Attributes:
        pose: estimated pose (x, y, theta) of the robot (base frame) in the map frame.
        covariance: 3x3 covariance of (x, y, theta).
        map_updated: whether the scan was inserted into the map.
        residual: mean squared residual of the finest match (0 = perfect fit, 1 = nothing matched).
    """

    pose: np.ndarray
    covariance: np.ndarray
    map_updated: bool
    residual: float = 0.0


@dataclass
class _MotionState:
    """Last estimates used for the update thresholds and the motion prediction."""

    last_pose: Optional[np.ndarray] = None
    last_stamp: Optional[float] = None
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    last_update_pose: Optional[np.ndarray] = None
    residual_mean: Optional[float] = None
    recoveries: int = 0


class HectorSlam:
    """Multi-resolution grid SLAM for one 2D laser.

    Args:
        params: map size and resolution, update factors and thresholds.

    .. note::
        Scan points are given in the robot (base) frame together with the laser origin in that frame;
        the estimated pose is the base frame's pose in the map frame, whose origin is the first pose
        (or the pose given to :meth:`reset`).
    """

    def __init__(self, params: SlamParams) -> None:
        self.params = params
        if params.map_multi_res_levels < 1:
            raise ValueError("map_multi_res_levels must be >= 1")
        side = params.map_size * params.map_resolution
        corner = (-params.map_start_x * side, -params.map_start_y * side)
        self.levels: list[GridLevel] = []
        for i in range(params.map_multi_res_levels):
            size = max(params.map_size >> i, 2)
            self.levels.append(GridLevel(size, side / size, corner,
                                         params.update_factor_free, params.update_factor_occupied))
        self.start_pose = np.zeros(3)
        self._state = _MotionState()
        self.pose = np.zeros(3)
        self.covariance = np.diag(COVARIANCE_FLOOR)

    # ---- control -------------------------------------------------------------------------------
    def reset(self, pose: Optional[np.ndarray] = None) -> None:
        """Clear every level and restart from ``pose`` (default the origin); the next scan is inserted."""
        for level in self.levels:
            level.reset()
        self.start_pose = np.zeros(3) if pose is None else np.array(pose, dtype=np.float64)
        self.pose = self.start_pose.copy()
        self._state = _MotionState()

    def set_pose(self, pose: np.ndarray) -> None:
        """Move the estimate without touching the map (the next match starts from here)."""
        self.pose = np.array(pose, dtype=np.float64)
        self._state.last_pose = None
        self._state.velocity = np.zeros(3)

    @property
    def has_map(self) -> bool:
        """Whether a scan has been inserted since the last reset."""
        return self._state.last_update_pose is not None

    # ---- processing ----------------------------------------------------------------------------
    def process(self, points: np.ndarray, laser_origin: np.ndarray, stamp: Optional[float] = None,
                yaw_change: Optional[float] = None) -> SlamStep:
        """Match one scan (points (N, 2) in the base frame) and update the map if the robot moved enough.

        yaw_change: how much the robot turned since the last scan processed, measured by another sensor
        (an IMU or compass; not in the original): the match starts from the last yaw turned by it instead of
        a yaw predicted from the last matches. Why: a turn of 2 rad/s with scans dropped under load (a
        fifth of a second between the scans processed) leaves the prediction 0.4 rad or more off, beyond
        the rotation search; the match settles on a wrong heading and the map is written in it.

        Raises ValueError when the scan has fewer than MIN_SCAN_POINTS points.
        """
        points = np.asarray(points, np.float64)
        if points.ndim != 2 or points.shape[1] != 2 or points.shape[0] < MIN_SCAN_POINTS:
            raise ValueError(f"need at least {MIN_SCAN_POINTS} scan points, got {points.shape}")
        st = self._state
        residual = 0.0
        if st.last_update_pose is None:
            pose = self.pose.copy()
            cov = np.diag(COVARIANCE_FLOOR)
        else:
            predicted = self._predict(stamp)
            if yaw_change is not None and math.isfinite(yaw_change):
                predicted[2] = wrap_angle(self.pose[2] + yaw_change)
            guess = predicted
            if self.params.rotation_search:
                # The last pose competes with the prediction: a wrong velocity (from a poor match) must
                # not feed back into the next guess and run away.
                bases = [predicted] if np.allclose(predicted, self.pose) else [predicted, self.pose]
                guess = best_start(self.levels[-1], points, bases, ROTATION_SEARCH_OFFSETS)
            result = self._coarse_to_fine(points, guess)
            if self.params.recovery_search and self._fits_badly(result.residual):
                result = self._recover(points, predicted, result)
            pose, residual = result.pose, result.residual
            w = RESIDUAL_AVERAGE_WEIGHT
            st.residual_mean = residual if st.residual_mean is None else (1 - w) * st.residual_mean + w * residual
            cov = self._covariance(result.hessian, residual, points.shape[0])
        updated = self._should_update(pose)
        if updated:
            self.insert(points, laser_origin, pose)
        self._remember(pose, stamp)
        self.pose = pose
        self.covariance = cov
        return SlamStep(pose.copy(), cov, updated, residual)

    @property
    def recoveries(self) -> int:
        """How many times the recovery search replaced a match since the last reset."""
        return self._state.recoveries

    def _coarse_to_fine(self, points: np.ndarray, guess: np.ndarray) -> MatchResult:
        """Match on every level from the coarsest to the finest, each starting where the last ended."""
        result = None
        for i in reversed(range(len(self.levels))):
            iters = ITERATIONS_FINE if i == 0 else ITERATIONS_COARSE
            result = match_level(self.levels[i], points, guess, iters,
                                 ITERATION_EXTENSION if self.params.iterate_to_convergence else 1)
            guess = result.pose
        assert result is not None
        return result

    def _fits_badly(self, residual: float) -> bool:
        """Whether a match fits much worse than the recent ones."""
        mean = self._state.residual_mean
        return mean is not None and residual > max(RECOVERY_MIN_RESIDUAL, RECOVERY_FACTOR * mean)

    def _recover(self, points: np.ndarray, predicted: np.ndarray, first: MatchResult) -> MatchResult:
        """Best of the first match and coarse-to-fine matches from the best grid candidates."""
        t = np.asarray(RECOVERY_TRANSLATIONS)
        r = np.asarray(RECOVERY_ROTATIONS)
        dx, dy, dth = np.meshgrid(t, t, r, indexing="ij")
        cands = predicted + np.stack((dx.ravel(), dy.ravel(), dth.ravel()), axis=1)
        scores = residuals(self.levels[-1], points, cands)
        best = first
        for k in np.argsort(scores)[:RECOVERY_CANDIDATES]:
            res = self._coarse_to_fine(points, cands[k])
            if res.residual < best.residual:
                best = res
        if best is not first:
            self._state.recoveries += 1
        return best

    def insert(self, points: np.ndarray, laser_origin: np.ndarray, pose: np.ndarray) -> None:
        """Insert a scan into every level at ``pose`` (beams from the laser origin to the points)."""
        world = transform_points(pose, points)
        origin = transform_points(pose, np.reshape(np.asarray(laser_origin, np.float64), (1, 2)))[0]
        for level in self.levels:
            level.update(origin, world)
        self._state.last_update_pose = np.array(pose, dtype=np.float64)

    # ---- helpers -------------------------------------------------------------------------------
    def _should_update(self, pose: np.ndarray) -> bool:
        """First scan, or moved more than the distance threshold / turned more than the angle one."""
        last = self._state.last_update_pose
        if last is None:
            return True
        moved = math.hypot(pose[0] - last[0], pose[1] - last[1])
        turned = abs(wrap_angle(pose[2] - last[2]))
        return (moved > self.params.map_update_distance_thresh
                or turned > self.params.map_update_angle_thresh)

    def _predict(self, stamp: Optional[float]) -> np.ndarray:
        """Initial guess for the next match: the last pose, moved at the last velocity if enabled."""
        st = self._state
        if not self.params.use_motion_prediction or st.last_pose is None:
            return self.pose.copy()
        dt = 1.0 if (stamp is None or st.last_stamp is None) else stamp - st.last_stamp
        if not (0.0 < dt < 1.0) and stamp is not None:
            return self.pose.copy()
        guess = self.pose + st.velocity * dt
        guess[2] = wrap_angle(guess[2])
        return guess

    def _remember(self, pose: np.ndarray, stamp: Optional[float]) -> None:
        """Keep the last pose and velocity (per second, or per scan without stamps)."""
        st = self._state
        if st.last_pose is not None:
            dt = 1.0 if (stamp is None or st.last_stamp is None) else stamp - st.last_stamp
            if dt > 0.0:
                diff = pose - st.last_pose
                diff[2] = wrap_angle(diff[2])
                st.velocity = diff / dt
        st.last_pose = pose.copy()
        st.last_stamp = stamp

    @staticmethod
    def _covariance(hessian: np.ndarray, residual: float, n: int) -> np.ndarray:
        """sigma^2 H^-1, with sigma^2 the residual variance of the fit, plus a small floor."""
        sigma2 = residual * n / max(n - 3, 1)
        try:
            cov = sigma2 * np.linalg.inv(hessian)
        except np.linalg.LinAlgError:
            cov = np.diag([1e3, 1e3, 1e3])
        if not np.all(np.isfinite(cov)):
            cov = np.diag([1e3, 1e3, 1e3])
        cov = 0.5 * (cov + cov.T) + np.diag(COVARIANCE_FLOOR)
        return cov
