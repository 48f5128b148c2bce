"""UGV tasks: go_to (2D path planning around the building), search_indoor (through the door).

extinguish_indoor_fire is the shared indoor task (tasks/indoor.py) with the UGV's straight `move`.
"""
from __future__ import annotations

import math

from mbzirc_arena.buildings import in_footprint, standing_at
from mbzirc_arena.routing import plan_2d

from .. import constants as C
from ..agent_task import AgentTask, TaskError
from ..leg_guard import LegGuard
from .indoor import SearchIndoor


class UgvGoTo(AgentTask):
    """Drive to a waypoint (z ignored): a 2D plan around the building footprints, leg by leg.

    Args (task_args): straight (False): one straight leg (indoors, through the door), stopped and failed
    when the laser sees a return ahead on it (leg_guard.py).
    """
    INPUT_KEYS = ['waypoint']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.guard = LegGuard(self)

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
                self.guard.move((x, y, here[2]), leg_yaw, what, tolerance=0.4)
            else:
                a.move_to(self, (x, y, here[2]), leg_yaw, what, tolerance=0.4)
        self.result['message'] = f'at ({target[0]:.1f}, {target[1]:.1f})'
        return C.SUCCESS


class UgvSearchIndoor(SearchIndoor):
    """Drive (planned) to the first waypoint - by default outside the door - then straight inside.

    .. note:: A UGV already inside (a second search after the first found nothing) cannot plan to the
       entrance around the building from within it: it searches the path back the way it came, from its
       nearest waypoint, since each straight leg of the path can be driven both ways.
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
            return super().run(_UD(ud.floor, back))
        self.feedback('GOING', 'to the entrance')
        self.call_task_or_raise('go_to', {'waypoint': path[0]})
        ud_path = path[1:] if len(path) > 1 else path
        return super().run(_UD(ud.floor, ud_path))

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
