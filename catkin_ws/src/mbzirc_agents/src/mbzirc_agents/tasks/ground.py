"""UAV ground-fire tasks: look_for_ground_fires, extinguish_ground_fire.

The blanket UAV flies a path with its downward thermal camera until a new ground fire is confirmed by the
estimator; to cover it, it descends over it while centring it in the downward image and drops the
blanket below the release height.
"""
from __future__ import annotations

import math

import numpy as np
from std_srvs.srv import Trigger
from mbzirc_arena.boxes import column_box, swept_box

from .. import constants as C
from ..control import GroundFireCentering
from ..agent_task import AgentTask, TaskError
from ..geometry import lawnmower
from .common import fire_position, parse_fire, parse_path
from .sensing import SensedObjects
from .uav_motion import hold_box


def gen_look_for_ground_fires(goal, agent) -> dict:
    """LookForGroundFires goal -> userdata (optional path)."""
    return {'path': parse_path(goal.path, agent)}


def gen_ground_fire(goal, agent) -> dict:
    """A goal naming a ground fire."""
    return {'fire_id': parse_fire(goal.fire_id, agent, (C.SUBTYPE_GROUND,))}


class LookForGroundFires(AgentTask):
    """Fly a path (default: lawn-mower over ~ground_search_area) with the downward thermal camera."""
    INPUT_KEYS = ['path']

    def run(self, ud) -> str:
        a = self.agent
        if ud.path:
            path = [(pos, yaw) for pos, yaw in ud.path]
        else:
            h = a.p.ground_search_height
            path = [(p, None) for p in lawnmower(a.p.ground_search_area, a.p.ground_search_spacing, h)]
        known = {int(o.id) for o in a.fires((C.SUBTYPE_GROUND,))}

        def new_fire() -> bool:
            return a.p.stop_at_first_fire and any(
                int(o.id) not in known for o in a.fires((C.SUBTYPE_GROUND,)))
        margin = a.p.region_margin
        for i, (wp, yaw) in enumerate(path):
            self.feedback('SEARCHING', f'leg {i + 1}/{len(path)}')
            here = a.position()
            a.reserve(self, 'go_to', swept_box(here[:3], wp, margin))
            arrived = a.move_to(self, wp, yaw, f'search leg {i + 1}/{len(path)}', stop_when=new_fire)
            a.reserve(self, 'hold', hold_box(a, a.position()))
            a.free('go_to')
            if not arrived:
                break
            if self._dwell(new_fire):              # stopped here: the frame filter gets its frames
                break
        ids = [int(o.id) for o in a.fires((C.SUBTYPE_GROUND,))]
        self.result['fire_ids'] = ids
        self.result['message'] = f'active ground fires: {ids}' if ids else 'no ground fire found'
        return C.SUCCESS


    def _dwell(self, new_fire) -> bool:
        """At a waypoint, watch the downward camera for ~ground_check_time s; when it reports a fire,
        wait up to ~confirm_time for the estimator's track. True when a new fire is known."""
        a = self.agent
        end = a.backend.now() + a.p.ground_check_time
        while a.backend.now() < end and not new_fire():
            if a.fire_detected():
                self.feedback('CHECKING', 'the downward camera sees a fire: waiting for its estimate')
                self.wait_until(new_fire, a.p.confirm_time)
                break
            self.sleep(0.25)
        return new_fire()

    def wait_until(self, cond, seconds: float) -> None:
        """Poll cond for up to seconds (no error when it stays false)."""
        end = self.agent.backend.now() + seconds
        while not cond() and self.agent.backend.now() < end:
            self.sleep(0.25)


class ExtinguishGroundFire(AgentTask):
    """Fly over the fire, descend while centring it, release the blanket, climb back."""
    INPUT_KEYS = ['fire_id']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.sensed = SensedObjects(self)

    def run(self, ud) -> str:
        a = self.agent
        if not a.blanket_attached:
            raise TaskError('no blanket attached: go home for a new one first')
        fire = np.array(fire_position(a, ud.fire_id))
        self.sensed.clear()
        h = a.p.ground_search_height
        self.feedback('APPROACHING', f'over fire {ud.fire_id}')
        self.call_task_or_raise('go_to', {'waypoint': ((fire[0], fire[1], fire[2] + h), None)})
        half = a.p.hold_half_size
        a.reserve(self, 'descend', column_box(fire[0], fire[1], fire[2], fire[2] + h + half, half + 1.0))
        ctl = GroundFireCentering(release_height=a.p.blanket_release_height)
        try:
            self._descend(ctl, fire, ud.fire_id)
            self.feedback('RELEASING', f'releasing the blanket over fire {ud.fire_id}')
            a.trigger(a.iface.add_client('actuators_system/release_blanket', Trigger), 'release_blanket')
            self.wait_for(lambda: not a.blanket_attached, 5.0, 'the blanket to fall')
        finally:
            self.feedback('CLIMBING', 'climbing back')
            p = a.position()
            try:
                a.move_to(self, (p[0], p[1], fire[2] + h), None, 'climb back')
            finally:
                a.free('descend')
        a.set_object_status(ud.fire_id, C.STATUS_EXTINGUISHED)
        self.result.update(extinguished=True, message=f'blanket released over fire {ud.fire_id}')
        return C.SUCCESS

    def _descend(self, ctl: GroundFireCentering, fire, fire_id: int) -> None:
        a = self.agent
        start = a.backend.now()
        while True:
            self.check_preempt()
            if a.backend.now() - start > a.p.centering_timeout:
                raise TaskError(f'could not centre fire {fire_id} in {a.p.centering_timeout:.0f} s')
            det = self.sensed.recent_fire(0.5)
            target = fire[:2] if det is None or det[2] != C.CAMERA_DOWNWARD else np.array(det[0][:2])
            p = a.position()
            if ctl.ready(p, target, fire[2]):
                return
            a.send_velocity(ctl.velocity(p, target, fire[2]))
            self.feedback('DESCENDING', f'fire {fire_id}: {math.hypot(*(target - p[:2])):.2f} m off, '
                                        f'z {p[2]:.1f}')
            a.backend.sleep(1.0 / C.CONTROL_RATE_HZ)
