"""UAV fire tasks: search_facade, go_to_facade_fire, extinguish_facade_fire, look_for_ground_fires,
extinguish_ground_fire.

The tasks sense through the robot's own detectors (`sensed_objects`, `thermal_detection/fire_detected`)
and the shared `/estimated_objects`; control loops run at the control rate and give up after a timeout.
"""
from __future__ import annotations

import math
import threading
from typing import Optional

import numpy as np
from mbzirc_comm_objs.msg import ObjectDetectionList
from std_srvs.srv import Trigger

from .. import constants as C
from ..control import GroundFireCentering, HoleCentering, pick_hole, world_to_body, yaw_rate_to
from ..framework import AgentTask, TaskError
from ..geometry import column_box, facade_standoff, lawnmower, swept_box
from .common import fire_position, floor_of, parse_fire, parse_floor, parse_path
from .uav_motion import hold_box

CAM_OFFSET_X = 0.15      # base_link -> camera_color_optical_frame (docs/interfaces.md)


def gen_search_facade(goal, agent) -> dict:
    """SearchFacade goal -> userdata (floor 0..2, optional standoff path)."""
    return {'floor': parse_floor(goal.floor), 'path': parse_path(goal.path, agent)}


def gen_facade_fire(goal, agent) -> dict:
    """A goal naming a facade fire."""
    d = float(getattr(goal, 'distance', 0.0))
    if not math.isfinite(d) or d < 0 or d > 10:
        raise ValueError(f'distance must be in [0, 10] m, got {d}')
    return {'fire_id': parse_fire(goal.fire_id, agent, (C.SUBTYPE_FACADE,)), 'distance': d}


def gen_look_for_ground_fires(goal, agent) -> dict:
    """LookForGroundFires goal -> userdata (optional path)."""
    return {'path': parse_path(goal.path, agent)}


def gen_ground_fire(goal, agent) -> dict:
    """A goal naming a ground fire."""
    return {'fire_id': parse_fire(goal.fire_id, agent, (C.SUBTYPE_GROUND,))}


class SensedObjects:
    """Latest detections of the robot's own detectors, kept by a task-dependent callback."""

    def __init__(self, task: AgentTask) -> None:
        self.task = task
        self.lock = threading.Lock()
        self.holes: list = []            # (body-frame point, radius m)
        self.holes_time = -1e9
        self.fire: Optional[tuple] = None  # (arena position, body relative position, camera direction)
        self.fire_time = -1e9
        task.iface.add_subscriber(task.name, 'sensed_objects', ObjectDetectionList, self.on_msg)

    def on_msg(self, msg: ObjectDetectionList) -> None:
        """Split holes (converted to the body frame) and fires."""
        a = self.task.agent
        now = a.backend.now()
        holes = []
        for d in msg.objects:
            p = d.pose.pose.position
            if not all(map(math.isfinite, (p.x, p.y, p.z))):
                a.backend.logerr_throttle(5.0, 'sensed_objects: NaN position, ignored')
                continue
            if d.type == C.TYPE_HOLE:
                b = self._to_body(d.header.frame_id, (p.x, p.y, p.z))
                if b is not None:
                    holes.append((b, float(d.scale.x)))
            elif d.type == C.TYPE_FIRE:
                r = d.relative_position
                with self.lock:
                    self.fire = ((p.x, p.y, p.z), (r.x, r.y, r.z), d.image_detection.camera_direction)
                    self.fire_time = now
        if holes:
            with self.lock:
                self.holes, self.holes_time = holes, now

    def _to_body(self, frame: str, p) -> Optional[np.ndarray]:
        frame = frame.lstrip('/')
        if frame.endswith('optical_frame'):               # x right, y down, z forward
            return np.array([p[2] + CAM_OFFSET_X, -p[0], -p[1]])
        if frame.endswith('base_link'):
            return np.array(p)
        if frame in ('', C.GLOBAL_FRAME):
            pose = self.task.agent.position()
            return world_to_body(np.array(p) - pose[:3], pose[3])
        self.task.agent.backend.logerr_throttle(5.0, f'sensed_objects: hole in unknown frame {frame!r}')
        return None

    def recent_holes(self, max_age: float) -> list:
        with self.lock:
            return list(self.holes) if self.task.agent.backend.now() - self.holes_time <= max_age else []

    def recent_fire(self, max_age: float) -> Optional[tuple]:
        with self.lock:
            return self.fire if self.task.agent.backend.now() - self.fire_time <= max_age else None


def choose_hole(holes: list) -> Optional[np.ndarray]:
    """The middle circle of a holder (hole between two decoys) among (body point, radius) circles.

    Uses the circle_detector library's choice when it is installed (it checks spacing and radii), else
    the middle one by lateral position.
    """
    try:
        from circle_detector.hole_choice import choose_middle_hole
    except ImportError:
        return pick_hole([h for h, _ in holes]) if len(holes) >= 3 else None
    optical = [(-h[1], -h[2], h[0] - CAM_OFFSET_X, r) for h, r in holes]   # x right, y down, z forward
    i = choose_middle_hole(optical)
    return None if i is None else holes[i][0]


class SearchFacade(AgentTask):
    """Visit the facade fire holders of a floor; at each, face it and ask the forward thermal camera."""
    INPUT_KEYS = ['floor', 'path']

    def run(self, ud) -> str:
        a = self.agent
        stops = [(pos, yaw, None) for pos, yaw in ud.path] if ud.path else self._holder_stops(ud.floor)
        if not stops:
            raise TaskError(f'no facade fire holders on floor {ud.floor}')
        found: list = []
        for i, (pos, yaw, holder) in enumerate(stops):
            self.feedback('GOING', f'holder {i + 1}/{len(stops)}')
            if self.call_task('go_to', {'waypoint': (pos, yaw)}) != C.SUCCESS:
                raise TaskError(f'holder {i + 1}: {self.last_sub_result.get("message")}')
            self.feedback('CHECKING', f'holder {i + 1}/{len(stops)}: looking with the thermal camera')
            self.sleep(1.0)                              # let the frame filter forget the last holder
            if not self._hot(float(a.p['check_fire_time'])):
                self.feedback('SKIPPING', f'holder {i + 1}/{len(stops)} is cold')
                continue
            fid = self._track_near(holder if holder is not None else self._ahead(pos, yaw))
            if fid is None:
                self.feedback('SKIPPING', f'holder {i + 1}: hot but no estimated fire there')
                continue
            found.append(fid)
            self.feedback('FOUND', f'fire {fid} at holder {i + 1}/{len(stops)}')
            if a.p['stop_at_first_fire']:
                break
        self.result['fire_ids'] = found
        self.result['message'] = (f'active facade fires on floor {ud.floor}: {found}' if found
                                  else f'no active facade fire found on floor {ud.floor}')
        return C.SUCCESS

    def _holder_stops(self, floor: int) -> list:
        """Standoff poses of the floor's holders, nearest first (greedy tour from here)."""
        a = self.agent
        holders = [tuple(h) for h in a.p.get('facade_holders', C.FACADE_HOLDERS) if floor_of(h[2]) == floor]
        here = a.position()[:2]
        tour = []
        while holders:
            h = min(holders, key=lambda q: math.hypot(q[0] - here[0], q[1] - here[1]))
            holders.remove(h)
            pos, yaw = facade_standoff(h, C.BUILDINGS, float(a.p['facade_standoff']))
            tour.append((pos, yaw, h))
            here = pos[:2]
        return tour

    @staticmethod
    def _ahead(pos, yaw):
        return (pos[0] + 2.0 * math.cos(yaw or 0.0), pos[1] + 2.0 * math.sin(yaw or 0.0), pos[2])

    def _hot(self, seconds: float) -> bool:
        end = self.agent.backend.now() + seconds
        while self.agent.backend.now() < end:
            if self.agent.fire_detected():
                return True
            self.sleep(0.25)
        return False

    def _track_near(self, point) -> Optional[int]:
        """Id of an ACTIVE facade fire within 2.5 m of point, waiting up to confirm_time for it."""
        end = self.agent.backend.now() + float(self.agent.p['confirm_time'])
        while True:
            for o in self.agent.fires((C.SUBTYPE_FACADE,)):
                q = o.pose.pose.position
                if math.dist((q.x, q.y, q.z), point) <= 2.5:
                    return int(o.id)
            if self.agent.backend.now() > end:
                return None
            self.sleep(0.25)


class GoToFacadeFire(AgentTask):
    """Fly to the standoff pose in front of a facade fire, facing the facade."""
    INPUT_KEYS = ['fire_id', 'distance']

    def run(self, ud) -> str:
        fire = fire_position(self.agent, ud.fire_id)
        dist = ud.distance or float(self.agent.p['facade_standoff'])
        pos, yaw = facade_standoff(fire, C.BUILDINGS, dist)
        self.feedback('GOING', f'to fire {ud.fire_id}, {dist:.1f} m in front of it')
        if self.call_task('go_to', {'waypoint': (pos, yaw)}) != C.SUCCESS:
            raise TaskError(self.last_sub_result.get('message', 'go_to failed'))
        self.result['message'] = f'in front of fire {ud.fire_id}'
        return C.SUCCESS


class ExtinguishFacadeFire(AgentTask):
    """Centre the hole at the nozzle (circle detector), pump while centred until cold or empty."""
    INPUT_KEYS = ['fire_id']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.sensed = SensedObjects(self)

    def run(self, ud) -> str:
        a = self.agent
        if a.water_empty():
            raise TaskError('tank empty: go home and refill first')
        fire = np.array(fire_position(a, ud.fire_id))
        ctl = HoleCentering(shoot_distance=float(a.p['shoot_distance']))
        pos, wall_yaw = facade_standoff(fire, C.BUILDINGS, ctl.shoot_distance)
        self.feedback('APPROACHING', f'to {ctl.shoot_distance:.1f} m in front of fire {ud.fire_id}')
        if self.call_task('go_to', {'waypoint': (pos, wall_yaw)}) != C.SUCCESS:
            raise TaskError(self.last_sub_result.get('message', 'go_to failed'))
        try:
            extinguished = self._shoot(ctl, fire, wall_yaw, ud.fire_id)
        finally:
            a.stop_pump()
            a.hold()
        if extinguished:
            a.set_object_status(ud.fire_id, C.STATUS_EXTINGUISHED)
        water = a.water_level if math.isfinite(a.water_level) else 0.0
        self.result.update(extinguished=bool(extinguished), water_left=max(0.0, water),
                           message=(f'fire {ud.fire_id} extinguished' if extinguished else
                                    f'fire {ud.fire_id} still hot, tank empty'))
        return C.SUCCESS

    def _target(self, fire, ctl) -> tuple:
        """Body-frame aim point and where it comes from: hole > own fire detection > estimate."""
        p = self.agent.position()
        holes = self.sensed.recent_holes(1.0)    # sim s: the circle detector runs at a few Hz on a busy CPU
        if holes:
            expected = world_to_body(fire - p[:3], p[3])
            middle = choose_hole(holes)
            if middle is not None and np.linalg.norm(middle[1:] - expected[1:]) < 1.0:
                return middle, 'hole'
            best = min((h for h, _ in holes), key=lambda h: np.linalg.norm(h[1:] - expected[1:]))
            if np.linalg.norm(best[1:] - expected[1:]) < 0.5:
                return best, 'hole'
        det = self.sensed.recent_fire(0.5)
        if det is not None and det[2] == C.CAMERA_FORWARD:
            return np.array(det[1]), 'thermal'
        return world_to_body(fire - p[:3], p[3]), 'estimate'

    def _shoot(self, ctl: HoleCentering, fire, wall_yaw: float, fire_id: int) -> bool:
        a = self.agent
        dt = 1.0 / C.CONTROL_RATE_HZ
        start = a.backend.now()
        centred_once = False
        pumping_since = None
        last_centred = -1e9
        cold_since = None
        last_check = -1e9
        while True:
            self.check_preempt()
            now = a.backend.now()
            if now - start > float(a.p['extinguish_timeout']):
                raise TaskError(f'not done after {a.p["extinguish_timeout"]:.0f} s')
            if not centred_once and now - start > float(a.p['centering_timeout']):
                raise TaskError(f'could not centre the hole in {a.p["centering_timeout"]:.0f} s')
            target, source = self._target(fire, ctl)
            p = a.position()
            if ctl.centred(target):
                centred_once, last_centred = True, now
                if pumping_since is None:
                    a.start_pump()
                    pumping_since = now
            elif pumping_since is not None and now - last_centred > 1.0:
                a.stop_pump()                           # off target: do not waste water
                pumping_since = None
            a.send_velocity(ctl.velocity(target, p[3]), yaw_rate_to(p[3], wall_yaw))
            state = 'SHOOTING' if pumping_since is not None else 'CENTERING'
            self.feedback(state, f'fire {fire_id}: aim on {source}, error '
                                 f'{np.linalg.norm(ctl.error(target)):.2f} m, water {a.water_level:.2f} L')
            if a.water_empty():
                return a.fire_detected() is False
            if pumping_since is not None and now - pumping_since > 2.0 and now - last_check > 0.5:
                last_check = now
                if a.fire_detected() is False:
                    cold_since = cold_since or now
                    if now - cold_since >= 1.0:
                        return True
                else:
                    cold_since = None
            a.backend.sleep(dt)


class LookForGroundFires(AgentTask):
    """Fly a path (default: lawn-mower over ~ground_search_area) with the downward thermal camera."""
    INPUT_KEYS = ['path']

    def run(self, ud) -> str:
        a = self.agent
        if ud.path:
            path = [(pos, yaw) for pos, yaw in ud.path]
        else:
            h = float(a.p['ground_search_height'])
            path = [(p, None) for p in lawnmower(a.p['ground_search_area'], float(a.p['ground_search_spacing']), h)]
        known = {int(o.id) for o in a.fires((C.SUBTYPE_GROUND,))}

        def new_fire() -> bool:
            return bool(a.p['stop_at_first_fire']) and any(
                int(o.id) not in known for o in a.fires((C.SUBTYPE_GROUND,)))
        margin = float(a.p['region_margin'])
        for i, (wp, yaw) in enumerate(path):
            self.feedback('SEARCHING', f'leg {i + 1}/{len(path)}')
            here = a.position()
            a.reserve(self, 'go_to', swept_box(here[:3], wp, margin))
            arrived = a.move_to(self, wp, yaw, f'search leg {i + 1}/{len(path)}', stop_when=new_fire)
            a.reserve(self, 'hold', hold_box(a, a.position()))
            a.free('go_to')
            if not arrived:
                break
        ids = [int(o.id) for o in a.fires((C.SUBTYPE_GROUND,))]
        self.result['fire_ids'] = ids
        self.result['message'] = f'active ground fires: {ids}' if ids else 'no ground fire found'
        return C.SUCCESS


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
        h = float(a.p['ground_search_height'])
        self.feedback('APPROACHING', f'over fire {ud.fire_id}')
        if self.call_task('go_to', {'waypoint': ((fire[0], fire[1], fire[2] + h), None)}) != C.SUCCESS:
            raise TaskError(self.last_sub_result.get('message', 'go_to failed'))
        half = float(a.p['hold_half_size'])
        a.reserve(self, 'descend', column_box(fire[0], fire[1], fire[2], fire[2] + h + half, half + 1.0))
        ctl = GroundFireCentering(release_height=float(a.p['blanket_release_height']))
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
            if a.backend.now() - start > float(a.p['centering_timeout']):
                raise TaskError(f'could not centre fire {fire_id} in {a.p["centering_timeout"]:.0f} s')
            det = self.sensed.recent_fire(0.5)
            target = fire[:2] if det is None or det[2] != C.CAMERA_DOWNWARD else np.array(det[0][:2])
            p = a.position()
            if ctl.ready(p, target, fire[2]):
                return
            a.send_velocity(ctl.velocity(p, target, fire[2]))
            self.feedback('DESCENDING', f'fire {fire_id}: {math.hypot(*(target - p[:2])):.2f} m off, '
                                        f'z {p[2]:.1f}')
            a.backend.sleep(1.0 / C.CONTROL_RATE_HZ)
