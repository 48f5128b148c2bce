"""UgvAgent: the UGV's tasks (go_to, search_indoor, extinguish_indoor_fire) on top of RobotAgent."""
from __future__ import annotations

from typing import Any, Dict

from mbzirc_arena.routing import path_length, plan_2d

from . import constants as C
from .robot_agent import RobotAgent
from .tasks import indoor, ugv, uav_motion as U
from .uav_agent import register_tasks

UGV_TASKS = [
    ('go_to', ugv.UgvGoTo, 'GoTo', U.gen_go_to, []),
    ('search_indoor', ugv.UgvSearchIndoor, 'SearchIndoor', indoor.gen_search_indoor_ugv, ['go_to', 'move']),
    ('extinguish_indoor_fire', indoor.ExtinguishIndoorFire, 'ExtinguishIndoorFire', indoor.gen_indoor_fire,
     ['move']),
]
UGV_SUB_TASKS = {'go_to': (ugv.UgvGoTo, {}), 'move': (ugv.UgvGoTo, {'straight': True})}

# The UGV's defaults where they differ from a UAV's (params.AgentParams).
UGV_DEFAULTS = {'use_regions': False, 'building_clearance': 1.2, 'max_speed': 1.0,
                'opening_keep_off': 0.9, 'frame_radius': 0.6,   # its 0.6 m radius in the 2.5 m door
                'leg_guard_half_width': 0.9, 'leg_guard_stop_distance': 1.1,   # the same radius + margins
                'wall_clearance': False,   # parked, it does not drift; a back-off aside is a manoeuvre for it
                'explore_in_sight': False,  # it explores the whole ground floor through its doorways
                # frontiers only: viewpoints for nearness (3.5 m) fell in its doorways, where its 0.9 m leg
                # guard holds it (a UGV search of another floor plan, test_explore_search)
                'explore_view_range': 0.0}


class UgvAgent(RobotAgent):
    """The UGV: drives around the building, enters through the door, puts out the indoor fire."""
    ROBOT_TYPE = 'ugv'

    def __init__(self, agent_id: str, backend: Any, params: Dict[str, Any], namespace: str = '') -> None:
        merged = dict(UGV_DEFAULTS)
        merged.update(params)
        super().__init__(agent_id, backend, merged, namespace)
        register_tasks(self, UGV_TASKS, UGV_SUB_TASKS)

    def check_point(self, p, what: str = 'waypoint') -> None:
        """The UGV ignores z: only x, y must be finite and inside the arena."""
        super().check_point((p[0], p[1], self.arena[2]), what)

    def is_moving_state(self) -> bool:
        return self.ual_state == C.UAL_FLYING_AUTO

    def cost_to_go_to(self, target) -> float:
        """Length of the planned 2D path (-1 when no path)."""
        here = self.position(wait=0.0)
        path = plan_2d(here[:2], target[:2], C.BUILDINGS, self.p.building_clearance)
        return -1.0 if path is None else path_length(path)
