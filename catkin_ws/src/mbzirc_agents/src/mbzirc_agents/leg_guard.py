"""Leg guard: an indoor straight leg stops before a laser return ahead, and fails saying so.

Why: indoors the legs are straight lines between the caller's waypoints, driven or flown on GNSS, whose
error is a metre or more and wanders. A leg whose end is truly inside a wall is driven into it (realistic
seed 106: the UGV's leg back towards an interior doorway, its GNSS fix about 1.6 m east of the truth by
where it hit, ended in the interior wall beside the doorway; no doorway was across the leg, so no laser
passage, and the straight drive went on into the wall, which stood in the laser's plane all the way). The
robot's own laser measures the walls as they are, whatever its GNSS error says.

Rules:
- the corridor of a leg is the strip ahead of the robot along the leg's horizontal direction (from where the
  robot is now to the leg's end: the UAL goes on to the set-point after the leg counts as arrived),
  `half_width` either side (the robot's half width plus a margin), its end rounded (a disc of that radius);
- a scan's returns are placed in the arena frame with the pose the robot had when the scan arrived, then
  seen from the pose of now (the robot moved since: at 1 m/s a scan 0.3 s old is 0.3 m nearer);
- the leg is blocked when at least MIN_BEAMS returns lie in the corridor no farther than `stop_distance`
  ahead of the robot's centre (the laser's origin): one stray return (noise) does not stop a leg, a wall
  gives dozens; REP 117 -inf (closer than the minimum range) counts as a return at the minimum range,
  NaN and +inf (no return) do not count;
- a leg with no more than the arrival tolerance to go is not guarded (the robot is there: it turns on the
  spot); returns beside or behind the robot never block (a door frame it passes, the wall it came through);
- without a fresh scan the leg goes on (a throttled error says so): the guard adds a check, it is not
  what moves the robot; a blind laser (a fresh scan whose every beam is NaN: no measurement at all, unlike
  +inf, nothing within range) blocks the leg: the walls it would see are unknown.
Pure geometry here (no ROS): `corridor_distances`, `blocking_distance` (the scan's returns: mbzirc_arena's
`laser.scan_points` with keep_near, REP 117); `LegGuard` is a
task's use of it (its scan subscription and the check passed to `RobotAgent.move_to`'s stop_when).
"""
from __future__ import annotations

import math
from typing import Any, Optional, Sequence, Tuple

import numpy as np
from mbzirc_arena.laser import scan_points
from sensor_msgs.msg import LaserScan

from . import constants as C
from .agent_task import TaskError
from .control import front_distance, nearest_return

MIN_BEAMS = 2              # returns in the corridor that make it blocked (one stray beam does not)

BLOCKS_THE_LEG = 'blocks the leg'    # the words of a leg's failure that the laser blocked (leg_blocked)


def blocked_reason(distance: float, target: Sequence[float], left: float, p) -> str:
    """Why a leg to target stopped: a return `distance` m ahead, `left` m of the leg still to go (p: the agent
    params of the guard). The words every blocked leg fails with (leg_blocked, the central unit's rules)."""
    return (f'a laser return {distance:.2f} m ahead {BLOCKS_THE_LEG} to ({target[0]:.1f}, {target[1]:.1f}) '
            f'({left:.1f} m left; guard: {p.leg_guard_stop_distance:.2f} m ahead, '
            f'+-{p.leg_guard_half_width:.2f} m aside)')


def leg_blocked(error: BaseException) -> bool:
    """True when a task failed because the laser found its leg blocked (the robot stopped short, holding)."""
    return BLOCKS_THE_LEG in str(error)


def corridor_distances(points: np.ndarray, origin: Sequence[float], direction: Sequence[float],
                       half_width: float, reach: float) -> np.ndarray:
    """Distances ahead (along the unit `direction`) of the points within half_width of the line from origin
    along direction, ahead of origin and no farther than reach."""
    if len(points) == 0:
        return np.zeros(0)
    u = np.asarray(direction, dtype=float)[:2]
    rel = np.asarray(points, dtype=float) - np.asarray(origin, dtype=float)[:2]
    along = rel @ u
    aside = rel @ np.array([-u[1], u[0]])
    keep = (along > 0.0) & (along <= reach) & (np.abs(aside) <= half_width)
    return along[keep]


def blocking_distance(points: np.ndarray, here: Sequence[float], target: Sequence[float], half_width: float,
                      stop_distance: float, min_leg: float) -> Optional[float]:
    """The distance ahead of the nearest return blocking the leg from here to target (x, y), None when it
    is clear or has no more than min_leg (its arrival tolerance) to go. A return blocks when it is at most
    stop_distance ahead and within half_width of the way still to go, to target itself (the UAL goes on to
    the set-point after the leg counts as arrived): a leg ending short of a wall is not blocked by it."""
    d = np.asarray(target[:2], dtype=float) - np.asarray(here[:2], dtype=float)
    length = float(np.hypot(d[0], d[1]))
    if length <= min_leg:
        return None
    u = d / length
    ahead = corridor_distances(points, here, u, half_width, stop_distance)
    if ahead.size:
        rel = np.asarray(points, dtype=float) - np.asarray(here[:2], dtype=float)
        along, aside = rel @ u, rel @ np.array([-u[1], u[0]])
        beyond = np.hypot(np.maximum(along - length, 0.0), aside)    # off the way to go (its end a disc)
        ahead = along[(along > 0.0) & (along <= stop_distance) & (beyond <= half_width)]
    return float(ahead.min()) if ahead.size >= MIN_BEAMS else None


def is_blind(ranges: Sequence[float]) -> bool:
    """True when no beam of a scan measured anything (every range NaN; REP 117 +-inf are measurements)."""
    r = np.asarray(ranges, dtype=float)
    return r.size > 0 and bool(np.all(np.isnan(r)))


def malformed(msg: LaserScan) -> bool:
    """True for a scan nothing can be placed from: no ranges, or angles not finite or not increasing."""
    return (not msg.ranges or not math.isfinite(msg.angle_min) or not math.isfinite(msg.angle_increment)
            or msg.angle_increment <= 0)


class LegGuard:
    """A motion task's view of its laser (`scan`): the check of its straight legs, and what the facade's
    velocity loop keeps off (the range ahead, the nearest return). One parser of the topic per task.

    Args:
        task: the AgentTask that moves.
    """

    def __init__(self, task: Any) -> None:
        self.task = task
        self.agent = task.agent
        self.reason = ''                                                 # why the last check blocked
        # the scans are the agent's (robot_agent.latest_scan: always on, so a leg checks the scan of before its
        # start, not none); bad input is reported while the task runs (the agent's cache stays silent)
        task.iface.add_subscriber(task.name, 'scan', LaserScan, self._report_bad)

    def _report_bad(self, msg: LaserScan) -> None:
        be = self.agent.backend
        if malformed(msg):
            be.logerr_throttle(5.0, f'[{self.task.name}] scan: empty or bad angles, ignored')
            return
        latest = self.agent.latest_scan()
        if latest[3] if latest is not None and latest[0] is msg else is_blind(msg.ranges):
            be.logerr_throttle(5.0, f'[{self.task.name}] scan: every beam NaN (laser blind): holding')

    def _fresh(self) -> Optional[Tuple[Any, np.ndarray]]:
        """(LaserScan, the pose of its arrival) of the agent's latest scan while fresh, else None."""
        scan = self.agent.latest_scan()
        if scan is None or scan[2] is None or self.agent.backend.now() - scan[1] > C.SCAN_MAX_AGE:
            return None
        return scan[0], scan[2]

    def points(self) -> Optional[np.ndarray]:
        """The latest fresh scan's returns in the arena frame (scan_points, with the pose of its arrival);
        None without a fresh scan."""
        fresh = self._fresh()
        if fresh is None:
            return None
        msg, then = fresh
        return scan_points(msg.ranges, msg.angle_min, msg.angle_increment, then, msg.range_min,
                           msg.range_max if msg.range_max > 0 else math.inf, keep_near=True)

    def blind(self) -> bool:
        """True while the latest usable scan, however old, is blind (every beam NaN): a laser that went blind
        and then silent still sees nothing (no velocity towards a wall it cannot see)."""
        scan = self.agent.latest_scan()
        return scan is not None and scan[3]

    def front_range(self) -> float:
        """Distance ahead to the wall the latest fresh scan sees (control.front_distance), inf without one."""
        fresh = self._fresh()
        if fresh is None:
            return math.inf
        msg = fresh[0]
        return front_distance(msg.ranges, msg.angle_min, msg.angle_increment)

    def nearest(self) -> Tuple[float, float]:
        """(distance, body angle) of the latest fresh scan's closest return (control.nearest_return), (inf, 0)
        without one."""
        fresh = self._fresh()
        if fresh is None:
            return math.inf, 0.0
        msg = fresh[0]
        return nearest_return(msg.ranges, msg.angle_min, msg.angle_increment, msg.range_min)

    def stop_when(self, target: Sequence[float], tolerance: float):
        """A stop_when for RobotAgent.move_to on the straight leg to target: True (and `reason` set) when the
        laser sees the leg blocked; always False with ~leg_guard off."""
        def blocked() -> bool:
            a = self.agent
            if not a.p.leg_guard:
                return False
            points = self.points()
            if points is None:
                a.backend.logerr_throttle(5.0, f'[{self.task.name}] leg guard: no fresh laser scan, the leg goes '
                                                'on unchecked')
                return False
            if self.blind():
                self.reason = 'the laser is blind (every beam of its scan NaN): holding'
                return True
            here = a.position()
            d = blocking_distance(points, here, target, a.p.leg_guard_half_width, a.p.leg_guard_stop_distance,
                                  tolerance)
            if d is None:
                return False
            left = math.hypot(target[0] - here[0], target[1] - here[1])
            self.reason = blocked_reason(d, target, left, a.p) + ': holding'
            return True
        return blocked

    def move(self, target: Sequence[float], yaw: Optional[float], what: str,
             tolerance: Optional[float] = None) -> None:
        """RobotAgent.move_to along the straight leg to target, guarded: TaskError (the robot holding) when
        the laser sees it blocked."""
        a = self.agent
        tol = a.p.position_tolerance if tolerance is None else tolerance
        blocked = self.stop_when(target, tol)
        if blocked() or not a.move_to(self.task, target, yaw, what, tolerance=tolerance, stop_when=blocked):
            a.backend.logwarn(f'[{self.task.name}] {what}: {self.reason}')
            raise TaskError(f'{what}: {self.reason}')


__all__ = ['LegGuard', 'MIN_BEAMS', 'blocking_distance', 'corridor_distances', 'is_blind', 'malformed']
