"""UavAgent: the UAV's tasks on top of RobotAgent."""
from __future__ import annotations

from typing import Any, Dict, Sequence

from mbzirc_comm_objs import msg as M

from . import constants as C
from .clearance_keeper import ClearanceKeeper
from .robot_agent import RobotAgent
from .tasks import facade as F, ground as G, indoor, uav_motion as U

# name, task class, action name (mbzirc_comm_objs.msg.<X>Action), gen_userdata, sub-tasks
UAV_TASKS = [
    ('take_off', U.TakeOff, 'TakeOff', U.gen_take_off, []),
    ('land', U.Land, 'Land', U.gen_empty, []),
    ('go_to', U.GoTo, 'GoTo', U.gen_go_to, []),
    ('follow_path', U.FollowPath, 'FollowPath', U.gen_follow_path, ['go_to']),
    ('hover', U.Hover, 'Hover', U.gen_hover, []),
    ('search_facade', F.SearchFacade, 'SearchFacade', F.gen_search_facade, ['go_to']),
    ('go_to_facade_fire', F.GoToFacadeFire, 'GoToFacadeFire', F.gen_facade_fire, ['go_to']),
    ('extinguish_facade_fire', F.ExtinguishFacadeFire, 'ExtinguishFacadeFire', F.gen_facade_fire, ['go_to']),
    ('look_for_ground_fires', G.LookForGroundFires, 'LookForGroundFires', G.gen_look_for_ground_fires, []),
    ('extinguish_ground_fire', G.ExtinguishGroundFire, 'ExtinguishGroundFire', G.gen_ground_fire, ['go_to']),
    ('enter_building', indoor.EnterBuilding, 'EnterBuilding', indoor.gen_enter_building, ['go_to', 'move']),
    # the search path's heights are the arena model's (floors, window heights): true heights
    ('search_indoor', indoor.SearchIndoor, 'SearchIndoor', indoor.gen_search_indoor_uav,
     [('move', {'true_height': True})]),
    ('extinguish_indoor_fire', indoor.ExtinguishIndoorFire, 'ExtinguishIndoorFire', indoor.gen_indoor_fire,
     ['move']),
    ('go_home_and_refill', U.GoHomeAndRefill, 'GoHomeAndRefill', U.gen_empty, ['go_to', 'land', 'take_off']),
]
# Sub-task name -> (class, task_args); a task's list may name one as (name, task_args it adds)
UAV_SUB_TASKS = {'go_to': (U.GoTo, {}), 'move': (U.GoTo, {'straight': True}), 'land': (U.Land, {}),
                 'take_off': (U.TakeOff, {})}


def register_tasks(agent: Any, tasks: list, sub_tasks: Dict[str, tuple]) -> None:
    """add_task every task of the table (and its sub-tasks)."""
    for name, cls, action, gen, subs in tasks:
        agent.add_task(name, cls, getattr(M, f'{action}Action'), gen,
                       getattr(M, f'{action}Result'), getattr(M, f'{action}Feedback'))
        for sub in subs:
            sub, extra = sub if isinstance(sub, tuple) else (sub, {})
            sub_cls, args = sub_tasks[sub]
            agent.add_sub_task(sub, name, sub_cls, {**args, **extra})


class UavAgent(RobotAgent):
    """A UAV: take-off, flight through reserved regions, facade / ground / indoor fires, refill.

    Every go-to and velocity it sends passes its clearance guard (clearance_keeper.py): never closer than
    ~min_clearance to the surface below by the altimeter, whatever the GNSS height says."""
    ROBOT_TYPE = 'uav'

    def __init__(self, agent_id: str, backend: Any, params: Dict[str, Any], namespace: str = '') -> None:
        super().__init__(agent_id, backend, params, namespace)
        self.clearance = ClearanceKeeper(self, super().send_waypoint)
        register_tasks(self, UAV_TASKS, UAV_SUB_TASKS)

    def start(self) -> None:
        super().start()
        self.backend.start_thread('clearance_guard', self.clearance.run)

    # ---- motion through the clearance guard ----------------------------------------------------------------
    def send_waypoint(self, x: float, y: float, z: float, yaw: float) -> None:
        self.clearance.waypoint(x, y, z, yaw)

    def send_velocity(self, v: Sequence[float], yaw_rate: float = 0.0) -> None:
        super().send_velocity(self.clearance.velocity(v), yaw_rate)

    def set_point_z(self, target: Sequence[float]) -> float:
        return self.clearance.set_point_z(float(target[0]), float(target[1]), float(target[2]))

    def _detectors_pose(self, msg: Any) -> Any:
        """agent/pose at the UAV's true height by its altimeter (the GNSS one without an estimate): the fire
        detector places fires with it, so a track's height is a true height whichever UAV saw the fire, and a
        task flies to it with at_true_height. Why: on GNSS heights a track carried the vertical error of the
        UAV that saw the fire (0.4 m std each); another UAV topping up a fire that read cold (nothing to aim
        at) flew its jet 0.36 m under where the first had put 1.1 L in, and put none in (realistic seed 101,
        rtf 4: in1_w left at 99.4 %)."""
        keeper = getattr(self, 'clearance', None)      # the pose callback may run before __init__ ends
        z = None if keeper is None else keeper.true_height_of(msg.pose.position.z)
        return msg if z is None else self._pose_msg_at(msg, msg.pose.position.x, msg.pose.position.y, z)

    def at_true_height(self, target: Sequence[float]) -> tuple:
        """target (x, y, z true: the arena model's) as the UAL flies it: z + the vertical GNSS error its
        clearance guard estimates from the altimeter. Why: indoors a GNSS height 0.4 m off puts a UAV
        passing under a doorway's lintel into it (realistic seed 102). Without a fresh estimate: target as
        it is (warned, throttled)."""
        e = self.clearance.vertical_error()
        if e is None:
            self.backend.logerr_throttle(5.0, 'no usable altimeter estimate: a true height is flown at the '
                                              'GNSS height')
            return tuple(float(v) for v in target[:3])
        return float(target[0]), float(target[1]), float(target[2]) + e

    def return_home(self) -> Any:
        """After a long heartbeat loss: go home and land (and take the reset if it comes)."""
        if self.ual_state not in C.UAL_FLYING:     # not flying: stay where we are
            return None
        try:
            return self.submit('go_home_and_refill', {}, force=True)
        except RuntimeError as e:
            self.backend.logwarn(f'cannot go home now: {e}')
            self._went_home = False
            return None
