"""Goal parsing shared by the task modules: every check a bad goal must fail, with a clear message."""
from __future__ import annotations

import math
from typing import Any, Optional, Tuple

from mbzirc_arena.c3 import floor_of  # noqa: F401  (the tasks' floor rule is the arena's)
from mbzirc_arena.yaw import yaw_from_quaternion

from .. import constants as C


def parse_pose(ps: Any, agent: Any, what: str = 'waypoint', check: bool = True
               ) -> Tuple[Tuple[float, float, float], Optional[float]]:
    """((x, y, z), yaw or None) of a PoseStamped goal field; ValueError when unusable.

    An empty frame_id means the arena frame; the all-zero quaternion means "keep the current yaw".
    """
    frame = ps.header.frame_id.lstrip('/')
    if frame not in ('', C.GLOBAL_FRAME):
        raise ValueError(f'{what} frame {ps.header.frame_id!r} is not {C.GLOBAL_FRAME!r}')
    p, q = ps.pose.position, ps.pose.orientation
    if not all(math.isfinite(v) for v in (q.x, q.y, q.z, q.w)):
        raise ValueError(f'{what} orientation has NaN')
    pos = (float(p.x), float(p.y), float(p.z))
    if check:
        agent.check_point(pos, what)
    return pos, yaw_from_quaternion(q.x, q.y, q.z, q.w)


def parse_path(path: Any, agent: Any, what: str = 'path') -> list:
    """[((x, y, z), yaw)] of a PoseStamped[] goal field."""
    return [parse_pose(ps, agent, f'{what}[{i}]') for i, ps in enumerate(path)]


def parse_floor(floor: int, allowed: Tuple[int, ...] = (0, 1, 2)) -> int:
    """floor as int; ValueError when not one of allowed."""
    if int(floor) not in allowed:
        raise ValueError(f'floor {floor} is not one of {list(allowed)}')
    return int(floor)


def parse_fire(fire_id: int, agent: Any, sub_types: Tuple[int, ...] = ()) -> int:
    """fire_id when /estimated_objects holds such a fire (of one of sub_types); ValueError otherwise."""
    obj = agent.fire(fire_id)
    if sub_types and obj.sub_type not in sub_types:
        names = {C.SUBTYPE_FACADE: 'facade', C.SUBTYPE_GROUND: 'ground', C.SUBTYPE_INDOOR: 'indoor',
                 C.SUBTYPE_UNKNOWN: 'unknown'}
        raise ValueError(f'fire {fire_id} is a {names.get(obj.sub_type, obj.sub_type)} fire, '
                         f'not {"/".join(names[s] for s in sub_types)}')
    return int(fire_id)


def fire_position(agent: Any, fire_id: int) -> Tuple[float, float, float]:
    """Current estimate of a fire's position (TaskError when the fire vanished from the estimator)."""
    from ..agent_task import TaskError
    try:
        p = agent.fire(fire_id).pose.pose.position
    except ValueError as e:
        raise TaskError(str(e))
    return float(p.x), float(p.y), float(p.z)
