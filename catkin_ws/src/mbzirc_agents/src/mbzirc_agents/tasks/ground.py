"""UAV ground-fire tasks: look_for_ground_fires, extinguish_ground_fire.

The blanket UAV flies a path with its downward thermal camera until a new ground fire is confirmed by the
estimator; to cover it, it descends over it while centring it in the downward image and drops the
blanket below the release height.

Why the release is steered by the image and never by the estimate: the estimate is placed in the frame of
the GNSS fixes of whoever saw the fire, each off by up to about a metre and drifting, while the UAV flies on
its own fix. The fire's offset in the downward image is relative to the UAV and free of both errors.
For the same reason the fire may be out of the image when the UAV arrives over the estimate: it then
searches around it (a square spiral whose legs the camera's footprint covers) before giving up.
"""
from __future__ import annotations

import math
from typing import List, Optional

import numpy as np
from std_srvs.srv import Trigger
from mbzirc_arena.boxes import column_box, swept_box

from .. import constants as C
from ..control import GroundFireCentering, body_to_world, saturate
from ..agent_task import AgentTask, TaskError
from ..geometry import lawnmower
from .common import fire_position, parse_fire, parse_path
from .sensing import SensedObjects
from .uav_motion import hold_box

SIGHT_MAX_AGE = 0.5     # s: an older downward sighting neither steers the descent nor allows the release
# m between the UAV and the fire's centre in the downward image at the release: the blanket (the team's own,
# larger than the plate by more than this on every side) must land over the whole plate
RELEASE_TOLERANCE = 0.25
SEARCH_OVERLAP = 0.8    # neighbouring legs of the search spiral are this fraction of the footprint apart
SEARCH_POINT_REACHED = 0.3   # m from a search point at which the UAV turns to the next


def footprint_half_width(height: float, fov_deg: float) -> float:
    """m of ground on each side of a downward camera at `height` m with a `fov_deg` field of view."""
    return max(0.0, height) * math.tan(math.radians(fov_deg) / 2.0)


def square_spiral(centre, half_width: float, radius: float) -> List[np.ndarray]:
    """Corners of a square spiral out from centre (centre first) whose swath, `half_width` on each side of
    every leg, covers the disc of `radius` m around centre without gaps.

    Parallel legs are one ring (SEARCH_OVERLAP x 2 half_width) apart; the spiral stops at the first ring
    whose swath reaches radius, after closing it (the last leg runs along its side where it started)."""
    c = np.asarray(centre[:2], dtype=float)
    if half_width <= 0.0:
        return [c]
    ring = SEARCH_OVERLAP * 2.0 * half_width
    rings = max(0, math.ceil((radius - half_width) / ring))
    points, here = [c], np.zeros(2)
    headings = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)]
    lengths = [k for k in range(1, 2 * rings + 1) for _ in (0, 1)] + ([2 * rings] if rings else [])
    for i, n in enumerate(lengths):
        here = here + n * ring * np.asarray(headings[i % 4])
        points.append(c + here)
    return points


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
        spiral = self._search_spiral(fire)
        reach = max(float(np.max(np.abs(q - fire[:2]))) for q in spiral)
        a.reserve(self, 'descend', column_box(fire[0], fire[1], fire[2], fire[2] + h + half,
                                              half + max(1.0, reach)))
        ctl = GroundFireCentering(release_height=a.p.blanket_release_height, tolerance=RELEASE_TOLERANCE)
        try:
            self._descend(ctl, fire, ud.fire_id, spiral)
            self.feedback('RELEASING', f'releasing the blanket over fire {ud.fire_id}')
            a.trigger(a.iface.add_client('actuators_system/release_blanket', Trigger), 'release_blanket')
            self.wait_for(lambda: not a.blanket_attached, 5.0, 'the blanket to fall')
            # covered now, whatever the climb back does: a failed climb must not leave the fire ACTIVE (the
            # central unit sent the next blanket to it: realistic seed 108, twice 'never seen' over it)
            a.set_object_status(ud.fire_id, C.STATUS_EXTINGUISHED)
        finally:
            self.feedback('CLIMBING', 'climbing back')
            p = a.position()
            try:
                a.move_to(self, (p[0], p[1], fire[2] + h), None, 'climb back')
            finally:
                a.free('descend')
        self.result.update(extinguished=True, message=f'blanket released over fire {ud.fire_id}')
        return C.SUCCESS

    def _search_spiral(self, fire) -> List[np.ndarray]:
        """The search points around the estimate: the footprint of the downward camera (its field of view
        ~downward_camera_fov) at ~ground_search_height covers ~ground_fire_search_radius around it."""
        p = self.agent.p
        return square_spiral(fire[:2], footprint_half_width(p.ground_search_height, p.downward_camera_fov),
                             p.ground_fire_search_radius)

    def _search(self, ctl: GroundFireCentering, fire, fire_id: int, spiral) -> np.ndarray:
        """Fly the spiral at the search height until the downward camera sees the fire; returns where it
        put the fire (UAV's own frame). Dwells ~ground_check_time at its first and last point (the
        detector's frame filter). TaskError ('never seen') when the spiral or ~ground_fire_search_time ends
        first: the fire is covered already, or its estimate is further off than the radius."""
        a = self.agent
        top = fire[2] + a.p.ground_search_height
        start = a.backend.now()
        i, reached = 0, None               # the search point flown to; when the current one was reached
        while True:
            self.check_preempt()
            now = a.backend.now()
            p = a.position()
            offset = self._sighted_offset(p)
            if offset is not None:
                return p[:2] + offset
            if reached is None and np.hypot(*(spiral[i] - p[:2])) <= SEARCH_POINT_REACHED:
                reached = now
            dwell = a.p.ground_check_time if i in (0, len(spiral) - 1) else 0.0
            if reached is not None and now - reached >= dwell:
                if i == len(spiral) - 1:
                    break
                i, reached = i + 1, None
            if now - start > a.p.ground_fire_search_time:
                break
            v = np.zeros(3)
            v[:2] = saturate(ctl.gain * (spiral[i] - p[:2]), ctl.vmax)
            v[2] = float(np.clip(ctl.gain * (top - p[2]), -ctl.descent_speed, ctl.descent_speed))
            a.send_velocity(v)
            self.feedback('SEARCHING', f'fire {fire_id} not in the downward image: search point '
                                       f'{i + 1}/{len(spiral)}, z {p[2]:.1f}')
            a.backend.sleep(1.0 / C.CONTROL_RATE_HZ)
        raise TaskError(f'fire {fire_id} never seen by the downward camera within '
                        f'{a.p.ground_fire_search_radius:.1f} m of its estimate ({len(spiral)} search points, '
                        f'{a.backend.now() - start:.0f} s): covered already, or the estimate is further off: '
                        'blanket kept')

    def _descend(self, ctl: GroundFireCentering, fire, fire_id: int, spiral) -> None:
        """Down to the release height centred on the fire in the downward image; returns when a fresh
        sighting has it under the UAV within RELEASE_TOLERANCE at that height.

        Not seen from over the estimate: the search spiral first (`_search`). Out of sight afterwards
        (lost: a gust at low height, where the image covers less than a metre, puts the fire out of view)
        the UAV stops descending and climbs back towards the search height, where the view is widest, over
        the place it last saw the fire. Why not go on towards the estimate: in the UAV's GNSS frame it may
        be a metre off (realistic seed 103: the blanket dropped beside the fire, which burned on)."""
        a = self.agent
        top = fire[2] + a.p.ground_search_height
        seen_xy = self._search(ctl, fire, fire_id, spiral)   # where the camera last put the fire (own frame)
        start = a.backend.now()
        while True:
            self.check_preempt()
            if a.backend.now() - start > a.p.centering_timeout:
                raise TaskError(f'could not centre fire {fire_id} in {a.p.centering_timeout:.0f} s after '
                                'seeing it (downward camera: lost or not centred): blanket kept')
            p = a.position()
            offset = self._sighted_offset(p)
            if offset is not None:
                seen_xy = p[:2] + offset
                if ctl.ready(p, seen_xy, fire[2]):
                    return
                v = ctl.velocity(p, seen_xy, fire[2])
                what = f'{np.hypot(*offset):.2f} m off in the image'
            else:
                v = ctl.velocity(p, seen_xy, fire[2])
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
