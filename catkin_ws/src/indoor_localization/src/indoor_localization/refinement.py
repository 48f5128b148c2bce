"""OutlineRefinement: the anchor's refinement by the building outline seen in the scans (outline.py), wired to
the anchored pose (anchor.IndoorPose) as the node runs it, without ROS: the node feeds it live, the bag
replay (bench/replay_slam_bag.py) feeds it a recorded trial, and both run the same code.

Rules: each scan is paired with the SLAM pose of the same stamp, at most every `scan_period` s; outdoors
(GNSS valid) the observations older than `outdoor_memory` s go first; a change of the SLAM map frame (a
jump, a new map) starts the refinement again; the correction applied follows the fitted one through a
CorrectionSmoother (rate-limited without a fix, at once on GNSS and for `crossing_at_once` s after its loss).
"""
from __future__ import annotations

import math
from collections import deque
from typing import Callable, Optional

from mbzirc_arena.laser import scan_points

from .anchor import IndoorPose
from .outline import IDENTITY, CorrectionSmoother, OutlineRefiner, RefineParams, outline_faces

SCAN_STAMP_MATCH = 1e-3      # s: a scan and the SLAM pose hector_mapping made of it share their stamp


def _quiet(_msg: str) -> None:
    return None


class OutlineRefinement:
    """Feed it the scans (`on_scan`, any object with header.stamp, ranges, angle_min, angle_increment,
    range_min, range_max) and, after each `IndoorPose.on_slam`, `update`. `info` / `warn` take its log lines."""

    def __init__(self, arena, params: RefineParams = RefineParams(), correction_rate: float = 1.0,
                 yaw_correction_rate: float = 0.1, scan_period: float = 0.2, outdoor_memory: float = 10.0,
                 laser_offset: tuple = (0.0, 0.0), info: Optional[Callable[[str], None]] = None,
                 warn: Optional[Callable[[str], None]] = None, crossing_at_once: float = 1.0) -> None:
        self.refiner = OutlineRefiner(outline_faces(arena.footprints), params)
        self.smoother = CorrectionSmoother(correction_rate, yaw_correction_rate)
        self.scan_period = scan_period
        self.outdoor_memory = outdoor_memory      # s of observations kept while GNSS is valid
        self.crossing_at_once = crossing_at_once  # s after the fix is lost while a new correction applies at once
        self.laser_offset = laser_offset
        self.info, self.warn = info or _quiet, warn or _quiet
        self.scans: deque = deque(maxlen=10)        # (stamp s, LaserScan) waiting for their SLAM pose
        self.last = -math.inf
        self.frame_changes = 0
        self.state = None                          # (observed, yaw_observed) last logged

    def on_scan(self, msg) -> None:
        self.scans.append((msg.header.stamp.to_sec(), msg))

    def update(self, core: IndoorPose, t: float, pose: tuple, z: float) -> None:
        """After core.on_slam for a SLAM pose (t, pose in the map frame); z: the robot's height (arena)."""
        if core.frame_changes != self.frame_changes:      # a SLAM jump: the kept walls are in an old frame
            self.frame_changes = core.frame_changes
            self.refiner.reset()
            self.smoother.reset()
            core.correction = IDENTITY
            self.warn("indoor_pose: outline: SLAM frame changed, refinement starts again")
        anchor = core.anchor
        if anchor is None:
            return
        if t - self.last >= self.scan_period or t < self.last:
            scan = next((m for st, m in tuple(self.scans) if abs(st - t) < SCAN_STAMP_MATCH), None)
            # outdoors the old observations go first; one fit for both (the scan's, or a refit)
            dropped = core.gnss_valid and self.refiner.forget_before(t - self.outdoor_memory, anchor, refit=False)
            found = []
            if scan is not None and math.isfinite(z):
                self.last = t
                pts = scan_points(scan.ranges, scan.angle_min, scan.angle_increment, range_min=scan.range_min,
                                  range_max=scan.range_max)
                found = self.refiner.on_scan(t, pose, z, anchor, pts, self.laser_offset, core.gnss_valid,
                                             float(scan.range_max))
                self._log()
            if dropped and not found:
                self.refiner.refit(anchor)
        at = anchor.apply(pose[0], pose[1], 0.0)[:2]
        # on GNSS nobody flies on this pose (the robots fly on the UAL's): the correction applies at once, so
        # that the pose is right when the fix goes; a direction first observed in the window's wall, 1 m
        # off, took a second at ~correction_rate and the first second indoors was 0.57 m off (realistic
        # seed 107 at rtf 4)
        # ... and in the window's wall, the first `crossing_at_once` s after the fix is lost: the inner faces seen
        # through the window give the direction along the facade there, and at ~correction_rate the first
        # second indoors was 0.5-0.64 m off (c3_floor_plan_b seed 101, realistic: both of UAV 2's flights);
        # a robot crossing a window is guided by its laser and odometer, not by this pose
        crossing = core.lost_at is not None and 0.0 <= t - core.lost_at <= self.crossing_at_once
        core.correction = self.smoother.step(t, self.refiner.correction.transform, at,
                                             at_once=core.gnss_valid or crossing)

    def _log(self) -> None:
        for e in self.refiner.pop_events():
            self.warn(f"indoor_pose: {e}")
        c = self.refiner.correction
        if (c.observed, c.yaw_observed) != self.state:
            self.state = (c.observed, c.yaw_observed)
            p = c.pivot
            x, y, _ = c.transform.apply(p[0], p[1], 0.0)
            self.info(f"indoor_pose: outline: {c.observed} direction(s) and {'the' if c.yaw_observed else 'no'} "
                      f"yaw observed on {c.walls} wall(s): correction ({x - p[0]:+.2f}, {y - p[1]:+.2f}) m, "
                      f"{c.transform.theta:+.3f} rad; walls {c.thickness:.2f} m thick")


__all__ = ["OutlineRefinement", "SCAN_STAMP_MATCH"]
