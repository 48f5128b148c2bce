"""UGV tasks: go_to (2D path planning around the building), search_indoor (through the door).

extinguish_indoor_fire is the shared indoor task (tasks/indoor.py) with the UGV's straight `move`, a leg
driven on set-points a short way ahead and checked against the laser at every step (GuardedDrive).
"""
from __future__ import annotations

import math

import numpy as np
from mbzirc_arena.buildings import in_footprint, standing_at
from mbzirc_arena.routing import plan_2d

from .. import constants as C
from ..agent_task import AgentTask, TaskError
from ..leg_guard import LegGuard, blocked_reason, blocking_distance, leg_blocked
from ..wall_clearance import back_off, wall_ahead
from .indoor import SearchIndoor

CARROT_MAX = 1.0         # m: the farthest ahead a guarded leg's set-point is placed (1 s at the UGV's speed)
CARROT_MIN = 0.1         # m: the nearest (still short of the guard's stop distance from a return ahead)
CARROT_RESEND = 0.3      # s between set-points moved on (sooner when one must be pulled back)
SCAN_WAIT = 2.0          # s a leg holds for a fresh laser scan that sees before it fails


class UgvGoTo(AgentTask):
    """Drive to a waypoint (z ignored): a 2D plan around the building footprints, leg by leg.

    Args (task_args): straight (False): one straight leg (indoors, through the door), stopped and failed
    when the laser sees a return ahead on it (GuardedDrive).
    """
    INPUT_KEYS = ['waypoint']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.guard = LegGuard(self)
        self.drive = GuardedDrive(self, self.guard)

    def run(self, ud) -> str:
        a = self.agent
        (target, yaw) = ud.waypoint
        here = a.position()
        if self.args.get('straight'):
            legs = [(target[0], target[1])]
        else:
            path = plan_2d(here[:2], target[:2], C.BUILDINGS, a.p.building_clearance)
            if path is None:
                raise TaskError(f'no path to ({target[0]:.1f}, {target[1]:.1f}) around the building')
            legs = path[1:]
        for i, (x, y) in enumerate(legs):
            last = i == len(legs) - 1
            leg_yaw = yaw if last and yaw is not None else math.atan2(y - a.position()[1], x - a.position()[0])
            what = f'leg {i + 1}/{len(legs)} to ({x:.1f}, {y:.1f})'
            if self.args.get('straight'):
                self.drive.leg((x, y, here[2]), leg_yaw, what, tolerance=0.4)
            else:
                a.move_to(self, (x, y, here[2]), leg_yaw, what, tolerance=0.4)
        self.result['message'] = f'at ({target[0]:.1f}, {target[1]:.1f})'
        return C.SUCCESS


class GuardedDrive:
    """A UGV's straight indoor leg on set-points at most CARROT_MAX ahead, its laser checked at every step.

    Why (realistic seed 108, benchmark and verification run): a go-to is driven to its set-point in the GNSS
    frame, and while it is under way (a turn on the spot included) the UAL moves the true set-point by every
    change of the GNSS error. The search path's waypoint 1.6 m off the interior wall ended, in truth, at its
    doorway's edge: the UGV hit the edge turning there to face the doorway (0.4 m moved in the turn), and in
    the other run, driving the same leg again after its guard had held it once, the guard saw the edge only
    at 0.67 m (a whole leg sent at once goes on at 1 m/s between the checks of a loaded agent). A set-point
    at most CARROT_MAX ahead, never nearer than the guard's stop distance to a return the laser sees ahead,
    bounds where the robot goes whatever the agent's delays; turns are yaw-rate commands (no translation).

    Rules: at every control step a set-point ahead along the leg (by GNSS), min(CARROT_MAX, the way left,
    the free way ahead beyond ~leg_guard_stop_distance) but at least CARROT_MIN, moved on every
    CARROT_RESEND s or at once when it must be pulled back; the leg guard's rule (leg_guard.py) blocks it:
    the robot stops, backs off from the returns nearer than ~min_wall_clearance (wall_clearance.back_off: the
    way it came, for a wall ahead) and the leg fails saying why (the central unit reassigns); no fresh scan,
    or a blind one (every beam NaN): the robot stops and waits, and the leg fails after SCAN_WAIT s; at its
    end it turns on the spot to the leg's yaw (UgvAgent.turn_on_the_spot). With ~leg_guard off: the go-to
    of old.
    """

    def __init__(self, task: AgentTask, guard: LegGuard) -> None:
        self.task, self.guard, self.agent = task, guard, task.agent

    def leg(self, target, yaw, what: str, tolerance: float) -> None:
        """Drive the straight leg to target (x, y), then turn to yaw (None: as it drove); TaskError (the
        robot stopped) when it cannot."""
        a = self.agent
        if not a.p.leg_guard:
            a.move_to(self.task, target, yaw, what, tolerance=tolerance)
            return
        try:
            self._leg(target, yaw, what, tolerance)
        except BaseException:
            a.hold()
            raise
        a.hold()
        if yaw is not None:
            a.turn_on_the_spot(self.task, yaw, f'{what}: turning')

    def _leg(self, target, yaw, what: str, tolerance: float) -> None:
        a, task = self.agent, self.task
        start = a.position()
        timeout = math.hypot(target[0] - start[0], target[1] - start[1]) / (0.5 * a.p.max_speed) + 20.0
        end = a.backend.now() + timeout
        unseen_since = None
        sent, sent_at = None, -math.inf          # the last set-point (x, y) and when
        while True:
            task.check_preempt()
            a.raise_if_crashed(what)
            a.raise_if_lost(what)
            here = a.position()
            way = np.array([target[0] - here[0], target[1] - here[1]])
            left = float(np.hypot(way[0], way[1]))
            if left <= tolerance:
                return
            if a.backend.now() > end:
                raise TaskError(f'{what}: not there after {timeout:.0f} s ({left:.1f} m left)')
            points = self.guard.points()
            if points is None or self.guard.blind():
                if sent is not None:
                    a.hold()
                    sent = None
                why = 'no fresh laser scan' if points is None else 'the laser is blind (every beam NaN)'
                unseen_since = a.backend.now() if unseen_since is None else unseen_since
                if a.backend.now() - unseen_since > SCAN_WAIT:
                    a.backend.logwarn(f'[{task.name}] {what}: {why} for {SCAN_WAIT:.0f} s: holding')
                    raise TaskError(f'{what}: {why} for {SCAN_WAIT:.0f} s: holding')
                a.backend.logerr_throttle(2.0, f'[{task.name}] {what}: {why}: holding')
                task.sleep(1.0 / C.CONTROL_RATE_HZ)
                continue
            unseen_since = None
            blocked = blocking_distance(points, here, target, a.p.leg_guard_half_width,
                                        a.p.leg_guard_stop_distance, tolerance)
            if blocked is not None:
                a.hold()
                self._blocked(points, here, target, blocked, left, what)
            u = way / left
            carrot = np.asarray(here[:2], dtype=float) + u * self.step(points, here, u, left)
            pull_back = sent is not None and float(np.dot(sent - carrot, u)) > CARROT_MIN
            if sent is None or pull_back or a.backend.now() - sent_at >= CARROT_RESEND:
                a.send_waypoint(float(carrot[0]), float(carrot[1]), float(target[2]),
                                here[3] if yaw is None else yaw)
                sent, sent_at = carrot, a.backend.now()
            task.feedback('MOVING', f'{what}: {left:.1f} m to go')
            task.sleep(1.0 / C.CONTROL_RATE_HZ)

    def step(self, points, here, u, left: float) -> float:
        """How far ahead along u the next set-point goes (see the class)."""
        p = self.agent.p
        free = wall_ahead(points, here, u, p.leg_guard_half_width, p.leg_guard_stop_distance + CARROT_MAX)
        room = CARROT_MAX if free is None else free - p.leg_guard_stop_distance
        return float(max(CARROT_MIN, min(CARROT_MAX, left, room)))

    def _blocked(self, points, here, target, blocked: float, left: float, what: str) -> None:
        """Back off from returns nearer than ~min_wall_clearance, and fail saying why."""
        a = self.agent
        reason = blocked_reason(blocked, target, left, a.p)
        off = back_off(points, here, a.p.min_wall_clearance, a.p.wall_clearance_margin)
        if off is not None:
            n = float(np.hypot(off[0], off[1]))
            a.backend.loginfo(f'[{self.task.name}] {what}: backing off {n:.2f} m from the returns nearer than '
                              f'{a.p.min_wall_clearance:.2f} m')
            a.move_to(self.task, (here[0] + off[0], here[1] + off[1], here[2]), here[3], f'{what}: backing off',
                      tolerance=min(0.1, 0.5 * n))
            reason += f': backed off {n:.2f} m'
        reason += ': holding'
        a.backend.logwarn(f'[{self.task.name}] {what}: {reason}')
        raise TaskError(f'{what}: {reason}')


class UgvSearchIndoor(SearchIndoor):
    """Drive (planned) to the first waypoint - by default outside the door - then straight inside.

    .. note:: A UGV already inside (a second search after the first found nothing) cannot plan to the
       entrance around the building from within it: it searches the path back the way it came, from its
       nearest waypoint, since each straight leg of the path can be driven both ways.

    A leg of the path that its laser finds blocked (GuardedDrive: the UGV stopped short of the wall and
    backed off) is not the search's end while waypoints follow (`~indoor_search plan`): the waypoint lies at
    a wall by the laser's measure (the path's waypoints carry the GNSS error, a metre or more), and the path
    goes on from where the UGV stands to the next one, whose leg passes the doorway the laser sees on it
    (tasks/passage.py: centred on the gap, through only one sensed wide enough for the frame) or is blocked
    in turn. Why (realistic seed 108): the path's waypoint 1.6 m east of the interior doorway was truly at
    the doorway's edge; the leg to it was held by the guard, the search failed, and again when sent again.
    """

    def run(self, ud) -> str:
        path = list(ud.path) or self.default_path()
        here = self.agent.position()
        if in_footprint(here, standing_at(here, C.BUILDINGS)):
            nearest = min(range(len(path)), key=lambda i: math.dist(path[i][0][:2], here[:2]))
            back = list(reversed(path[:nearest + 1]))
            if self.agent.p.indoor_search == 'explore':      # explore from here (tasks/explore.py)
                back = [(tuple(here[:3]), None)]
            self.feedback('GOING', f'already inside: searching back the way in from waypoint {nearest + 1}')
            return self._search(ud.floor, back)
        self.feedback('GOING', 'to the entrance')
        self.call_task_or_raise('go_to', {'waypoint': path[0]})
        self.agent.wait_for_indoor_pose(self, 'the door')
        ud_path = path[1:] if len(path) > 1 else path
        return self._search(ud.floor, ud_path)

    def _search(self, floor: int, path: list) -> str:
        """SearchIndoor.run along path, going on past waypoints whose legs the laser found blocked."""
        while True:
            self.reached = -1
            try:
                return super().run(_UD(floor, path))
            except TaskError as e:
                blocked = self.reached + 1
                if (self.agent.p.indoor_search == 'explore' or not leg_blocked(e)
                        or blocked >= len(path) - 1):
                    raise
                self.agent.backend.logwarn(f'[{self.name}] {e}: the waypoint is at a wall by the laser; going on to '
                                           f'the next one from here')
                path = path[blocked + 1:]

    def _look(self, floor: int, i: int, n: int, yaw) -> list:
        self.reached = i                       # the path's waypoint i was reached (the leg to it not blocked)
        return super()._look(floor, i, n, yaw)

    def default_path(self) -> list:
        p = self.agent.p
        out, ins = p.door_outside, p.door_inside
        into = math.atan2(ins[1] - out[1], ins[0] - out[0])
        z = self.agent.position()[2]
        if p.indoor_search == 'explore':       # exploring from just inside the door (tasks/explore.py)
            return [((out[0], out[1], z), into), ((ins[0], ins[1], z), None)]
        pts = [((out[0], out[1], z), into), ((ins[0], ins[1], z), into)]
        pts += [((q[0], q[1], z), q[2] if len(q) > 2 else None) for q in p.indoor_search_path]
        return pts


class _UD:
    """Minimal userdata (floor, path) for re-using SearchIndoor.run."""

    def __init__(self, floor, path) -> None:
        self.floor, self.path = floor, path
