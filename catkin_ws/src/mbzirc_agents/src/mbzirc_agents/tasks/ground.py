"""UAV ground-fire tasks: look_for_ground_fires, extinguish_ground_fire.

The blanket UAV flies a path with its downward thermal camera until a new ground fire is confirmed by the
estimator; to cover it, it descends over it while centring it in the downward image and drops the
blanket below the release height.

Why the release is steered by the image and never by the estimate: the estimate is placed in the frame of
the GNSS fixes of whoever saw the fire, each off by up to about a metre and drifting, while the UAV flies on
its own fix. The fire's offset in the downward image is relative to the UAV and free of both errors.
"""
from __future__ import annotations

from typing import Optional

import numpy as np
from std_srvs.srv import Trigger
from mbzirc_arena.boxes import column_box, swept_box

from .. import constants as C
from ..control import GroundFireCentering, body_to_world
from ..agent_task import AgentTask, TaskError
from ..geometry import lawnmower
from .common import fire_position, parse_fire, parse_path
from .sensing import SensedObjects
from .uav_motion import hold_box

SIGHT_MAX_AGE = 0.5     # s: an older downward sighting neither steers the descent nor allows the release
# m between the UAV and the fire's centre in the downward image at the release: the blanket (the team's own,
# larger than the plate by more than this on every side) must land over the whole plate
RELEASE_TOLERANCE = 0.25


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
        ctl = GroundFireCentering(release_height=a.p.blanket_release_height, tolerance=RELEASE_TOLERANCE)
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
        """Down to the release height centred on the fire in the downward image; returns when a fresh
        sighting has it under the UAV within RELEASE_TOLERANCE at that height.

        Out of sight (never seen yet, or lost: a gust at low height, where the image covers less than a
        metre, puts the fire out of view) the UAV stops descending and climbs back towards the search height,
        where the view is widest, over the place it last saw the fire (the estimate before the first
        sighting). Why not go on towards the estimate: in the UAV's GNSS frame it may be a metre off
        (realistic seed 103: the blanket dropped beside the fire, which burned on)."""
        a = self.agent
        start = a.backend.now()
        top = fire[2] + a.p.ground_search_height
        seen_xy = None                     # where the camera last put the fire, in the UAV's own frame
        while True:
            self.check_preempt()
            if a.backend.now() - start > a.p.centering_timeout:
                how = 'never seen' if seen_xy is None else 'not centred'
                raise TaskError(f'could not centre fire {fire_id} in {a.p.centering_timeout:.0f} s '
                                f'(downward camera: {how}): blanket kept')
            p = a.position()
            offset = self._sighted_offset(p)
            if offset is not None:
                seen_xy = p[:2] + offset
                if ctl.ready(p, seen_xy, fire[2]):
                    return
                v = ctl.velocity(p, seen_xy, fire[2])
                what = f'{np.hypot(*offset):.2f} m off in the image'
            else:
                v = ctl.velocity(p, fire[:2] if seen_xy is None else seen_xy, fire[2])
                v[2] = float(np.clip(ctl.gain * (top - p[2]), 0.0, ctl.descent_speed))   # never down blind
                what = 'out of sight of the downward camera: climbing over where it was'
            a.send_velocity(v)
            self.feedback('DESCENDING', f'fire {fire_id}: {what}, z {p[2]:.1f}')
            a.backend.sleep(1.0 / C.CONTROL_RATE_HZ)

    def _sighted_offset(self, p) -> Optional[np.ndarray]:
        """World xy offset from the UAV (pose p now) to the fire in a downward sighting at most SIGHT_MAX_AGE
        old: its body-relative position turned by the heading the image was taken with, less the UAV's own
        move since (both from its own pose: the GNSS error cancels); None without one."""
        a = self.agent
        det, stamp = self.sensed.latest_fire()
        if det is None or det[2] != C.CAMERA_DOWNWARD or a.backend.now() - stamp > SIGHT_MAX_AGE:
            return None
        rel = np.asarray(det[1], dtype=float)
        if not np.all(np.isfinite(rel)):
            return None
        then = a.pose_at(stamp)
        return body_to_world(rel, then[3])[:2] - (np.asarray(p[:2]) - then[:2])
