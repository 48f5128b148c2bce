"""When hector_mapping should match scans: near a building, or without a GNSS fix (no ROS).

The SLAM pose is used only without a fix, i.e. inside a building, and its anchor is fitted in the last
seconds before entering; away from the buildings a robot flies on GNSS and its scan matching is spent for
nothing (an eighth of the mission's CPU on three robots: it kept the mission under 3x real time on 2 cores),
and the map it writes there is one the robot never comes back to. So the matching is paused once the robot is,
on GNSS, further than `pause_beyond` from every building's footprint, and resumed on a new, empty map (the
anchor fitted again on its first pairs) once it comes within `resume_within`, from where it still has the
approach of a window or door ahead of it (seconds of pairs for the anchor, and the facade for the outline's
refinement). Without a fix the matching always runs: the SLAM pose is then the only one there is.
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

from mbzirc_arena.buildings import footprint_distance


class MappingGate:
    """Feed it the robot's reported position and whether the fix is valid; `update` says when hector_mapping
    should pause (False) or resume on a new map (True). A hysteresis (resume_within < pause_beyond) keeps a
    robot flying along the limit from resetting its map over and over."""

    def __init__(self, footprints: Sequence[Sequence[float]], resume_within: float = 8.0,
                 pause_beyond: float = 10.0):
        if pause_beyond > 0 and resume_within > pause_beyond:
            raise ValueError(f"resume_within ({resume_within} m) must not exceed pause_beyond ({pause_beyond} m)")
        self.footprints = tuple(footprints)
        self.resume_within = resume_within
        self.pause_beyond = pause_beyond       # <= 0: never paused
        self.running = True                    # hector_mapping starts matching

    def update(self, gnss_valid: bool, x: float, y: float) -> Optional[bool]:
        """The new state when it changes (True: resume on a new map, False: pause), else None."""
        if self.pause_beyond <= 0 or not gnss_valid:
            want = True
        elif not (math.isfinite(x) and math.isfinite(y)):
            want = self.running
        else:
            d = footprint_distance((x, y), self.footprints)
            want = d <= (self.pause_beyond if self.running else self.resume_within)
        if want == self.running:
            return None
        self.running = want
        return want


__all__ = ["MappingGate"]
