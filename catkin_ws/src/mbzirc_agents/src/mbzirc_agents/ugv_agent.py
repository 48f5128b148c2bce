"""UgvAgent: the UGV's tasks (go_to, search_indoor, extinguish_indoor_fire) on top of RobotAgent."""
from __future__ import annotations

import math
from typing import Any, Dict, Optional, Sequence

from mbzirc_arena.c3 import ARENA
from mbzirc_arena.routing import path_length, plan_2d
from mbzirc_arena.yaw import wrap_angle

from . import constants as C
from .agent_task import AgentTask, TaskError
from .control import yaw_rate_to
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
                'explore_in_sight': False}  # it explores the whole ground floor through its doorways


TURN_GAIN, TURN_MAX_RATE, TURN_MIN_RATE = 1.5, 0.8, 0.1   # 1/s, rad/s, rad/s: turning on the spot


class UgvAgent(RobotAgent):
    """The UGV: drives around the building, enters through the door, puts out the indoor fire."""
    ROBOT_TYPE = 'ugv'

    def __init__(self, agent_id: str, backend: Any, params: Dict[str, Any], namespace: str = '') -> None:
        merged = dict(UGV_DEFAULTS)
        merged.update(params)
        super().__init__(agent_id, backend, merged, namespace)
        register_tasks(self, UGV_TASKS, UGV_SUB_TASKS)

    def _detectors_pose(self, msg: Any) -> Any:
        """agent/pose on the ground (the arena's z 0, the tower's ground floor: the UGV drives on nothing else),
        so that its fire detector places fires at true heights as the UAVs' do (UavAgent._detectors_pose), not
        with its vertical GNSS error (0.3-0.5 m) in them."""
        return self._pose_msg_at(msg, msg.pose.position.x, msg.pose.position.y, ARENA.floor_heights[0])

    def check_point(self, p, what: str = 'waypoint') -> None:
        """The UGV ignores z: only x, y must be finite and inside the arena."""
        super().check_point((p[0], p[1], self.arena[2]), what)

    def is_moving_state(self) -> bool:
        return self.ual_state == C.UAL_FLYING_AUTO

    def move_to(self, task: AgentTask, target: Sequence[float], yaw: Optional[float], what: str,
                tolerance: Optional[float] = None, stop_when: Optional[Any] = None, **kwargs: Any) -> bool:
        """RobotAgent.move_to, but a waypoint within the tolerance of where the UGV is (a turn where it stands:
        a look around, facing a door) is turned on the spot on yaw-rate commands (turn_on_the_spot).
        Why (realistic seed 108): a go-to is under way in the GNSS frame while the UGV turns, and the UAL
        moves its true set-point by every change of the GNSS error meanwhile: turning to face an interior
        doorway, the UGV moved 0.4 m sideways onto the doorway's edge."""
        here = self.position()
        tol = self.p.position_tolerance if tolerance is None else tolerance
        if stop_when is None and yaw is not None and math.hypot(target[0] - here[0], target[1] - here[1]) <= tol:
            self.turn_on_the_spot(task, yaw, what)
            return True
        return super().move_to(task, target, yaw, what, tolerance=tolerance, stop_when=stop_when, **kwargs)

    def turn_on_the_spot(self, task: AgentTask, yaw: float, what: str) -> None:
        """Turn to yaw on yaw-rate commands (no translation whatever the GNSS error does), within
        ~yaw_tolerance; TaskError (stopped) when not there in time."""
        timeout = abs(wrap_angle(yaw - self.position()[3])) / TURN_MIN_RATE + 10.0
        end = self.backend.now() + timeout
        try:
            while True:
                task.check_preempt()
                self.raise_if_crashed(what)
                error = wrap_angle(yaw - self.position()[3])
                if abs(error) <= self.p.yaw_tolerance:
                    break
                if self.backend.now() > end:
                    raise TaskError(f'{what}: not turned after {timeout:.0f} s ({math.degrees(error):.0f} deg left)')
                rate = yaw_rate_to(0.0, error, gain=TURN_GAIN, max_rate=TURN_MAX_RATE)
                rate = math.copysign(max(abs(rate), TURN_MIN_RATE), rate)
                self.send_velocity((0.0, 0.0, 0.0), rate)
                task.feedback('MOVING', f'{what}: {math.degrees(error):.0f} deg to turn')
                self.backend.sleep(1.0 / C.CONTROL_RATE_HZ)
        finally:
            if self.is_moving_state():
                self.send_velocity((0.0, 0.0, 0.0), 0.0)

    def cost_to_go_to(self, target) -> float:
        """Length of the planned 2D path (-1 when no path)."""
        here = self.position(wait=0.0)
        path = plan_2d(here[:2], target[:2], C.BUILDINGS, self.p.building_clearance)
        return -1.0 if path is None else path_length(path)
