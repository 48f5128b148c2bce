"""The way a robot came inside a building, and backing out along it when no pose is trusted.

Why (issue 18, bad input): a SLAM pose that jumps, a map that stops, leave a robot indoors with no trusted
pose (pose source none); the running task fails and the central unit reassigns, but the robot itself stays
where it was when the pose went, often near a wall in a look-around or a doorway. Its way in is known free:
it flew it. With no trusted pose the UAL still dead-reckons (a few cm/s of drift, ual_sim README "No GNSS
indoors"), so the agent's position stays consistent over the seconds a back-out takes; the laser keeps it
off the walls whatever that drift does (robot_agent._keep_off_walls_without_pose first).

Rules:
- the trail is the robot's trusted positions (x, y) inside a building footprint below its roof, one every
  TRAIL_SPACING m, since it last came in (a trusted position outside clears it), at most TRAIL_POINTS;
- with no trusted pose for ~lost_back_out_after s, an idle moving robot goes back along it by velocity
  (at most BACK_OUT_SPEED), point after point (reached within BACK_OUT_REACHED m), towards where it came in;
  never out through the outline: the trail ends inside, and crossing a window or a door needs a pose;
- a laser return ahead within ~leg_guard_stop_distance on the way stops the back-out there (held);
- a trusted pose again ends it, and the trail goes on from where the robot is.
"""
from __future__ import annotations

import math
from collections import deque
from typing import Optional, Sequence

import numpy as np
from mbzirc_arena.buildings import in_footprint, standing_at

TRAIL_SPACING = 0.3      # m between two points of the trail
TRAIL_POINTS = 400       # points kept (120 m of way in)
BACK_OUT_SPEED = 0.3     # m/s at most (the UAL's dead reckoning, a frame of ~1 m, walls about)
BACK_OUT_GAIN = 1.0      # 1/s: velocity per metre to the next point
BACK_OUT_REACHED = 0.25  # m: a point of the trail this near is passed


class WayBack:
    """The trail in (record) and the velocity back along it (velocity); not thread-safe (the agent's state
    lock holds around record, its idle loop calls velocity)."""

    def __init__(self, footprints: Sequence[Sequence[float]]) -> None:
        self.footprints = footprints
        self.trail: deque = deque(maxlen=TRAIL_POINTS)
        self.backing = False      # a back-out is under way (points popped from the trail's end as reached)
        self.done = False         # it ended (trail's start reached or blocked): held until a pose returns
        self._end_reason: Optional[str] = None

    def record(self, position: Sequence[float]) -> None:
        """A trusted position (x, y, z): kept when inside a footprint below its roof, else the trail cleared."""
        self.backing = self.done = False
        if not in_footprint(position, standing_at(position, self.footprints)):
            self.trail.clear()
            return
        xy = (float(position[0]), float(position[1]))
        if not self.trail or math.dist(self.trail[-1], xy) >= TRAIL_SPACING:
            self.trail.append(xy)

    def velocity(self, here: Sequence[float], blocked_ahead) -> Optional[np.ndarray]:
        """(vx, vy) towards the next point back along the trail from here (the dead-reckoned position);
        None when there is no trail, at its start, or when the way is blocked (the last two end the back-out:
        `done`, and `take_end` says why once). blocked_ahead(direction) -> bool: a laser return ahead within
        the guard's distance along that unit direction."""
        if self.done or not self.trail:
            return None
        while self.trail and math.dist(self.trail[-1], here[:2]) <= BACK_OUT_REACHED:
            self.trail.pop()
        if not self.trail:
            return self._end('where it came in')
        way = np.subtract(self.trail[-1], here[:2])
        length = float(np.hypot(way[0], way[1]))
        u = way / length
        if blocked_ahead(u):
            return self._end('a laser return ahead on the way')
        self.backing = True
        return u * min(BACK_OUT_SPEED, BACK_OUT_GAIN * length)

    def _end(self, where: str) -> None:
        self.done, self._end_reason = True, where
        return None

    def take_end(self) -> Optional[str]:
        """Where the back-out ended (once), None otherwise."""
        where, self._end_reason = self._end_reason, None
        return where


__all__ = ['WayBack', 'TRAIL_SPACING', 'BACK_OUT_SPEED']
