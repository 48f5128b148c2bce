"""UAV facade tasks: search_facade, go_to_facade_fire, extinguish_facade_fire.

A water UAV visits the facade fire holders of a floor facing each one, asks its forward thermal camera
whether it is hot, and takes the estimator's track of a hot one; to put it out it centres the hole (the
middle of three circles of the circle detector) in front of its nozzle and pumps while centred.
"""
from __future__ import annotations

import math
from collections import deque
from typing import Optional

import numpy as np
from circle_detector import hole_choice
from geometry_msgs.msg import PointStamped
from mbzirc_arena.buildings import nearest_face, standing_at
from mbzirc_arena.holders import known_holder, nearest_holder

from .. import constants as C
from ..control import HoleCentering, body_to_world, keep_off_return, world_to_body, yaw_rate_to
from ..agent_task import AgentTask, TaskError
from ..geometry import facade_standoff, faces_wall
from .cold_check import NOT_SEEN_HOT, ColdConfirmation, WaterFlow, dry_tank_verdict
from .common import fire_position, floor_of, parse_fire, parse_floor, parse_path
from .outline_fix import laser_gnss_error, shifted
from .sensing import CAM_OFFSET_X, SensedObjects
from ..leg_guard import LegGuard

ASK_PERIOD = 1.0       # s at most between two CheckFire questions while watering a hole
STANDOFF_REFIX = 0.3   # m: a standoff reached on GNSS further than this from where the laser then puts it is flown again


def gen_search_facade(goal, agent) -> dict:
    """SearchFacade goal -> userdata (floor 0..2, optional standoff path)."""
    return {'floor': parse_floor(goal.floor), 'path': parse_path(goal.path, agent)}


def gen_facade_fire(goal, agent) -> dict:
    """A goal naming a facade fire."""
    d = float(getattr(goal, 'distance', 0.0))
    if not math.isfinite(d) or d < 0 or d > 10:
        raise ValueError(f'distance must be in [0, 10] m, got {d}')
    return {'fire_id': parse_fire(goal.fire_id, agent, (C.SUBTYPE_FACADE,)), 'distance': d}


def choose_hole(holes: list) -> Optional[np.ndarray]:
    """Body point of the hole to shoot among Holes: the circle the depth camera sees through, or the
    middle of three circles (hole between two decoys); None when no choice is safe (circle_detector's
    choice, which also checks spacing and radii)."""
    optical = [(-h.body[1], -h.body[2], h.body[0] - CAM_OFFSET_X, h.radius) for h in holes]  # x right, y down
    i = hole_choice.choose_hole(optical, [h.opening for h in holes])
    return None if i is None else holes[i].body


def keep_off_walls(p, v: np.ndarray, min_dist: float) -> np.ndarray:
    """v without its component toward the nearest wall when closer than min_dist (and a push away when
    closer than 0.8 x min_dist): whatever the detections say, the UAV never flies into the facade.
    Only walls that rise to the UAV's height count (not the extension's below a facade D fire)."""
    normal, d = nearest_face(p[:3], standing_at(p[:3], C.BUILDINGS))
    if normal is None or d >= min_dist:
        return v
    n = np.array([normal[0], normal[1], 0.0])
    v = np.array(v, dtype=float)
    toward = -float(v @ n)
    if toward > 0:
        v = v + toward * n
    if d < 0.8 * min_dist:
        v = v + 0.3 * n
    return v


class SearchFacade(AgentTask):
    """Visit the facade fire holders of a floor; at each, face it and ask the forward thermal camera.

    With a goal path, every pose that faces a wall within 3.5 m is a holder to check; the others are
    transit waypoints (corners between facades).
    """
    INPUT_KEYS = ['floor', 'path']

    def run(self, ud) -> str:
        a = self.agent
        stops = [(pos, yaw, None) for pos, yaw in ud.path] if ud.path else self._holder_stops(ud.floor)
        if not stops:
            raise TaskError(f'no facade fire holders on floor {ud.floor}')
        found: list = []
        for i, (pos, yaw, holder) in enumerate(stops):
            self.feedback('GOING', f'holder {i + 1}/{len(stops)}')
            self.call_task_or_raise('go_to', {'waypoint': (pos, yaw)}, f'holder {i + 1}')
            if holder is None and not faces_wall(pos, yaw, C.BUILDINGS):
                continue                                 # a transit waypoint (e.g. around a corner)
            self.feedback('CHECKING', f'holder {i + 1}/{len(stops)}: looking with the thermal camera')
            self.sleep(1.0)                              # let the frame filter forget the last holder
            if not self._hot(a.p.check_fire_time):
                self.feedback('SKIPPING', f'holder {i + 1}/{len(stops)} is cold')
                continue
            fid = self._track_near(holder if holder is not None else self._ahead(pos, yaw))
            if fid is None:
                self.feedback('SKIPPING', f'holder {i + 1}: hot but no estimated fire there')
                continue
            found.append(fid)
            self.feedback('FOUND', f'fire {fid} at holder {i + 1}/{len(stops)}')
            if a.p.stop_at_first_fire:
                break
        self.result['fire_ids'] = found
        self.result['message'] = (f'active facade fires on floor {ud.floor}: {found}' if found
                                  else f'no active facade fire found on floor {ud.floor}')
        return C.SUCCESS

    def _holder_stops(self, floor: int) -> list:
        """Standoff poses of the floor's holders, nearest first (greedy tour from here)."""
        a = self.agent
        holders = [tuple(h) for h in a.p.facade_holders if floor_of(h[2]) == floor]
        here = a.position()[:2]
        tour = []
        while holders:
            h = min(holders, key=lambda q: math.hypot(q[0] - here[0], q[1] - here[1]))
            holders.remove(h)
            pos, yaw = facade_standoff(h, C.BUILDINGS, a.p.facade_standoff)
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
        end = self.agent.backend.now() + self.agent.p.confirm_time
        while True:
            for o in self.agent.fires((C.SUBTYPE_FACADE,)):
                q = o.pose.pose.position
                if math.dist((q.x, q.y, q.z), point) <= 2.5:
                    return int(o.id)
            if self.agent.backend.now() > end:
                return None
            self.sleep(0.25)


HOLE_SEARCH_RADIUS = 2.0   # m: a hole the circle detector picks this close to the estimate or to its nearest
                           # known holder is the fire's (holders on a facade are >= 2.8 m apart)
LOOK_TIME = 4.0            # s aiming on the estimate with no hole or fire in sight before looking wider
WIDE_VIEW_EXTRA = 1.5      # m further back than the shooting distance to look wider: the RGB-D camera's
                           # +-27 deg vertical view covers ~+-0.7 m of facade at 1.5 m, ~+-1.5 m at 3 m
CENTRED_WINDOW = 2.0       # s of aim errors averaged to judge "centred" while gusts move the UAV
CENTRED_SPREAD_MAX = 0.4   # m: RMS wander about that average beyond which the jet is not on the hole


def look_point(fire) -> np.ndarray:
    """Where to look for a hole that is not in sight from the estimate: midway between the estimate and its
    nearest known holder when that is within HOLE_SEARCH_RADIUS (the hole is at one of the two, give or
    take the GNSS error), else the estimate."""
    fire = np.asarray(fire, dtype=float)
    holder, d = nearest_holder(fire)
    return (fire + holder) / 2.0 if d <= HOLE_SEARCH_RADIUS else fire


class CentringWindow:
    """Whether the jet is on the hole: now (within HoleCentering's tolerance), or on average over the last
    CENTRED_WINDOW s with a bounded wander.

    Why the average: gusts near the tower's first floor push a UAV 0.1-0.4 m about its set-point faster
    than the centring loop takes it back; the aim error then sweeps around the hole and may never lie
    within the tolerance on both axes at the same instant, though the jet hits the hole much of the time.
    """

    def __init__(self, ctl: HoleCentering, window: float = CENTRED_WINDOW,
                 spread_max: float = CENTRED_SPREAD_MAX) -> None:
        self.ctl, self.window, self.spread_max = ctl, window, spread_max
        self.samples: deque = deque()       # (time, body-frame aim point)

    def clear(self) -> bool:
        """Forget the errors (another target, or no target seen): False, not centred."""
        self.samples.clear()
        return False

    def update(self, target, now: float) -> bool:
        """One aim point (body frame) in; True when centred now or on average over the window."""
        target = np.asarray(target, dtype=float)
        self.samples.append((now, target))
        while now - self.samples[0][0] > self.window:
            self.samples.popleft()
        if self.ctl.centred(target):
            return True
        if now - self.samples[0][0] < 0.8 * self.window:
            return False                    # not enough history yet for an average
        points = np.array([t for _, t in self.samples])
        mean = points.mean(axis=0)
        spread = float(np.sqrt(((points[:, 1:] - mean[1:]) ** 2).sum(axis=1).mean()))
        return self.ctl.centred(mean) and spread <= self.spread_max


def outward_error(err: Optional[tuple], yaw: float) -> Optional[tuple]:
    """The part of a GNSS error err (GNSS less truth) that would put a UAV facing a wall (heading yaw) nearer
    to it than its GNSS fix says: its component along the wall's outward normal when positive, else none.
    Why only that part: the other way the UAV merely stands further out (the hole's centring closes the
    distance by the camera and the laser), while the GNSS-frame goal that part would give lies inside the
    building's known outline, which a go-to refuses (realistic seed 111: A_4's standoff refused three times,
    'waypoint (23.3, 19.3, 0.6) is inside the building outline', with a fix 1.5 m off away from facade A)."""
    if err is None:
        return None
    n = (-math.cos(yaw), -math.sin(yaw))
    along = err[0] * n[0] + err[1] * n[1]
    return (along * n[0], along * n[1]) if along > 0.0 else (0.0, 0.0)


def fly_to_standoff(task: AgentTask, guard: LegGuard, pos, yaw: float, what: str) -> None:
    """Go to a standoff placed from a facade's known plane (pos, facing yaw) moved out by the GNSS error the
    laser measures on the buildings' outline (outline_fix) that would put the UAV nearer the wall
    (`outward_error`), before the flight and again once there: flown again when it is more than STANDOFF_REFIX
    off (the error wandered on the way). Without an observation, on GNSS.
    Why (realistic seed 104, explore run): a UAV whose GNSS fix was 1.2-1.8 m off towards facade C flew its
    approach to the hole's standoff, 1.5 m out from the facade's known plane, into the facade."""
    err = outward_error(laser_gnss_error(task, guard, f'{what}, before the approach'), yaw)
    task.call_task_or_raise('go_to', {'waypoint': (shifted(pos, err), yaw)})
    err = outward_error(laser_gnss_error(task, guard, f'{what}, there'), yaw)
    here = task.agent.position()
    target = shifted(pos, err)
    if err is not None and math.hypot(target[0] - here[0], target[1] - here[1]) > STANDOFF_REFIX:
        task.call_task_or_raise('go_to', {'waypoint': (target, yaw)})


class GoToFacadeFire(AgentTask):
    """Fly to the standoff pose in front of a facade fire (its known holder), facing the facade (placed by the
    laser on the buildings' outline: fly_to_standoff)."""
    INPUT_KEYS = ['fire_id', 'distance']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.guard = LegGuard(self)            # its scans: the GNSS error by the laser on the outline

    def run(self, ud) -> str:
        fire = known_holder(fire_position(self.agent, ud.fire_id))
        dist = ud.distance or self.agent.p.facade_standoff
        pos, yaw = facade_standoff(fire, C.BUILDINGS, dist)
        self.feedback('GOING', f'to fire {ud.fire_id}, {dist:.1f} m in front of it')
        fly_to_standoff(self, self.guard, pos, yaw, f'{dist:.1f} m in front of fire {ud.fire_id}')
        self.result['message'] = f'in front of fire {ud.fire_id}'
        return C.SUCCESS


class ExtinguishFacadeFire(AgentTask):
    """Centre the hole at the nozzle (circle detector), pump while centred until cold or empty.

    Safety: the forward set-point never comes closer than `~min_wall_distance` to what the laser sees
    ahead (`scan`); once a hole is seen it is locked (its arena position) and a later hole further than
    C.HOLE_JUMP_MAX from it aborts the task instead of being chased; the pump stops when the fire is
    judged out (tasks/cold_check.py: seen hot centred on the locked hole, then C.COLD_CHECKS "no fire"
    answers in a row with water flowing into it). A fire never seen hot there gets ~top_up_time of water
    and is not reported out: the goal fails with why.
    """
    INPUT_KEYS = ['fire_id']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.sensed = SensedObjects(self)
        self.locked_hole: Optional[np.ndarray] = None
        self.locked_open = False                # the depth camera saw through the locked circle
        self.lock_count = 0                     # how many locks this run (a new lock resets "cold")
        self.guard = LegGuard(self)             # its laser: the outline fix, the range ahead, the nearest return
        # switches the (lazy) circle detector on while this task runs: holes arrive in sensed_objects
        self.iface.add_demand(self.name, C.HOLE_DEMAND_TOPIC, PointStamped)

    def keep_off_laser(self, v: np.ndarray, yaw: float, min_dist: float) -> np.ndarray:
        """v kept off the laser's nearest return (fresh scans only): walls as they are, whatever the GNSS
        error of the pose the arena model is placed with."""
        d, ang = self.guard.nearest()
        return keep_off_return(v, yaw, d, ang, min_dist)

    def run(self, ud) -> str:
        a = self.agent
        if a.water_empty():
            raise TaskError('tank empty: go home and refill first')
        fire = np.array(fire_position(a, ud.fire_id))
        self.locked_hole, self.locked_open, self.lock_count = None, False, 0
        self.dry_note = 'still hot, tank empty'
        self.sensed.clear()
        ctl = HoleCentering(shoot_distance=a.p.shoot_distance)
        pos, wall_yaw = facade_standoff(known_holder(fire), C.BUILDINGS, ctl.shoot_distance)
        self.feedback('APPROACHING', f'to {ctl.shoot_distance:.1f} m in front of fire {ud.fire_id}')
        fly_to_standoff(self, self.guard, pos, wall_yaw, f'{ctl.shoot_distance:.1f} m in front of fire {ud.fire_id}')
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
                                    f'fire {ud.fire_id} {self.dry_note}'))
        return C.SUCCESS

    def _target(self, fire) -> tuple:
        """Body-frame aim point and where it comes from: hole > own fire detection > estimate.

        Which circle is "the hole": at the first sight, the one circle_detector's choice names (seen
        through by the depth camera, or the middle of three) if it lies within 1 m of the estimate, else
        the circle nearest the estimate within 0.5 m. It is then locked (arena position) and followed:
        only a circle within C.HOLE_SAME_MAX of the lock is the same hole (the decoys sit 0.7 m aside);
        a circle the depth camera sees through replaces a lock that was not seen through (a decoy taken
        for the hole); nothing near the lock -> aim on the lock ("last hole"); every circle further than
        C.HOLE_JUMP_MAX -> abort rather than chase it near the wall.
        """
        p = self.agent.position()
        holes = self.sensed.recent_holes(1.0)    # sim s: the circle detector runs at a few Hz on a busy CPU
        if self.locked_hole is not None:
            if holes:
                worlds = [p[:3] + body_to_world(h.body, p[3]) for h in holes]
                jumps = [float(np.linalg.norm(w - self.locked_hole)) for w in worlds]
                if min(jumps) > C.HOLE_JUMP_MAX:
                    raise TaskError(f'hole estimate jumped {min(jumps):.1f} m (> {C.HOLE_JUMP_MAX} m): '
                                    'not chasing it near the wall')
                openings = [i for i, h in enumerate(holes)
                            if hole_choice.is_opening(h.opening) and jumps[i] <= C.HOLE_JUMP_MAX]
                if not self.locked_open and len(openings) == 1 and jumps[openings[0]] > C.HOLE_SAME_MAX:
                    i = openings[0]
                    self._lock(worlds[i], True, f'the camera sees through a circle {jumps[i]:.2f} m from '
                                                f'the locked one (a decoy): locked on it')
                    return np.asarray(holes[i].body, dtype=float), 'hole'
                i = int(np.argmin(jumps))
                if jumps[i] <= C.HOLE_SAME_MAX:
                    self.locked_hole = worlds[i]
                    self.locked_open = self.locked_open or hole_choice.is_opening(holes[i].opening)
                    return np.asarray(holes[i].body, dtype=float), 'hole'
            return world_to_body(self.locked_hole - p[:3], p[3]), 'last hole'
        seen = self.sensed.recent_fire(0.5)
        seen = np.array(seen[1]) if seen is not None and seen[2] == C.CAMERA_FORWARD else None
        if holes:
            # where the fire should be, body frame: where this robot's thermal camera sees it now (relative,
            # free of the GNSS error that the estimate, placed by other poses or other robots, carries)
            expected = seen if seen is not None else world_to_body(fire - p[:3], p[3])
            chosen = choose_hole(holes)
            best = None
            if chosen is not None and np.linalg.norm(chosen[1:] - expected[1:]) < 1.0:
                best = next(h for h in holes if h.body is chosen)
            else:
                near = min(holes, key=lambda h: np.linalg.norm(h.body[1:] - expected[1:]))
                if np.linalg.norm(near.body[1:] - expected[1:]) < 0.5:
                    best = near
            if best is None and seen is None and chosen is not None and self._fire_hole(p, chosen, fire):
                best = next(h for h in holes if h.body is chosen)
            if best is None:
                self.agent.backend.loginfo_throttle(
                    5.0, f'[{self.name}] {len(holes)} circle(s) in sight, none taken for the hole of the fire '
                         f'({"no safe choice" if chosen is None else "the chosen one is too far from it"})')
            if best is not None:
                body = np.asarray(best.body, dtype=float)
                self._lock(p[:3] + body_to_world(body, p[3]), hole_choice.is_opening(best.opening),
                           f'locked on a hole {np.linalg.norm(body[1:] - expected[1:]):.2f} m from the '
                           f'estimate ({"seen through" if hole_choice.is_opening(best.opening) else "not seen through"}'
                           f'{", middle of three" if best.body is chosen else ""})')
                return body, 'hole'
        if seen is not None:
            return seen, 'thermal'
        return world_to_body(fire - p[:3], p[3]), 'estimate'

    @staticmethod
    def _fire_hole(p, chosen: np.ndarray, fire) -> bool:
        """Whether circle_detector's chosen hole (body frame) is the fire's though far from the estimate: within
        HOLE_SEARCH_RADIUS of it or of its nearest known holder. Why: an estimate placed with a GNSS error
        may be 1.5 m off its hole (realistic seed 103), and only holders have holes."""
        world = p[:3] + body_to_world(chosen, p[3])
        holder, _ = nearest_holder(fire)
        return min(math.dist(world, fire), math.dist(world, holder)) <= HOLE_SEARCH_RADIUS

    def _lock(self, world: np.ndarray, seen_through: bool, why: str) -> None:
        """Lock on a hole; a new lock is a new target: its cold answers start again from zero."""
        self.locked_hole, self.locked_open = np.asarray(world, dtype=float), seen_through
        self.lock_count += 1
        self.agent.backend.loginfo(f'[{self.name}] {why} at ({world[0]:.2f}, {world[1]:.2f}, {world[2]:.2f})')

    def _shoot(self, ctl: HoleCentering, fire, wall_yaw: float, fire_id: int) -> bool:
        """Centre and pump until the fire is judged out (True) or the tank is empty.

        Centred: on what the cameras see (the hole, else the locked hole, else the thermal hot spot), now or
        on average over CENTRED_WINDOW s (CentringWindow: gusts). Never on the estimate alone: it carries the
        GNSS error of the poses that placed it; with nothing in sight from it for LOOK_TIME the UAV backs
        off WIDE_VIEW_EXTRA and looks around it and its nearest known holder (look_point).

        Out (tasks/cold_check.py): seen hot while centred on the locked hole (the watering pose), then
        C.COLD_CHECKS "no fire" answers in a row, each with the jet on the hole at that instant (within the
        tolerance, not only on average) and water flowing (the tank level dropping). A new lock starts again. A lock never seen hot gets ~top_up_time of water (a nearly quenched
        heater reads cold) and the goal then fails: cold there may mean the camera looks through the hole or
        at a decoy as much as "out" (was: out after 2 x C.COLD_CHECKS cold answers).
        """
        a = self.agent
        start = a.backend.now()
        centred_once = False
        pumping_since = None
        last_centred = -1e9
        cold, cold_lock = ColdConfirmation(), self.lock_count
        window = CentringWindow(ctl)
        wide = HoleCentering(shoot_distance=ctl.shoot_distance + WIDE_VIEW_EXTRA)
        flow: Optional[WaterFlow] = None                # watching the tank level while the pump runs
        blind_since = None                              # aiming on the estimate, nothing in sight, since
        unseen_water = 0.0                              # s of water on the lock while never seen hot
        last_check = last_ask = prev = -1e9
        while True:
            self.check_preempt()
            now = a.backend.now()
            step, prev = (now - prev if prev > 0 else 0.0), now
            if now - start > a.p.extinguish_timeout:
                raise TaskError(f'not done after {a.p.extinguish_timeout:.0f} s')
            if not centred_once and now - start > a.p.centering_timeout:
                raise TaskError(f'could not centre the hole in {a.p.centering_timeout:.0f} s')
            target, source = self._target(fire)
            if self.lock_count != cold_lock:            # another circle is the hole now: start again
                cold, cold_lock, unseen_water = ColdConfirmation(), self.lock_count, 0.0
                window.clear()
            p = a.position()
            steer = ctl
            if source == 'estimate':
                blind_since = now if blind_since is None else blind_since
                if now - blind_since > LOOK_TIME:
                    target, source, steer = world_to_body(look_point(fire) - p[:3], p[3]), 'wide view', wide
            else:
                blind_since = None
            on_hole = source in ('hole', 'last hole')
            # water only where this robot sees the fire or its hole: the estimate carries the GNSS error
            # of the poses that placed it (seen: a tank pumped beside a fire aimed on it)
            centred = (window.update(target, now) if source in ('hole', 'last hole', 'thermal')
                       else window.clear())
            if centred:
                centred_once, last_centred = True, now
                if pumping_since is None:
                    a.start_pump()
                    pumping_since, flow = now, WaterFlow(now)
            elif pumping_since is not None and now - last_centred > 1.0:
                a.stop_pump()                           # off target: do not waste water
                pumping_since, flow = None, None
            if flow is not None:
                flow.update(a.water_level, now)
                stalled = flow.stalled(now, fire_id)
                if stalled:
                    raise TaskError(stalled)
            min_wall = a.p.min_wall_distance
            v = steer.velocity(target, p[3], self.guard.front_range(), min_wall)
            v = self.keep_off_laser(keep_off_walls(p, v, min_wall), p[3], min_wall)
            if self.guard.blind():
                v = np.zeros(3)                         # bad input: hold, the timeouts decide the rest
            a.send_velocity(v, yaw_rate_to(p[3], wall_yaw))
            state = 'SHOOTING' if pumping_since is not None else 'LOOKING' if steer is wide else 'CENTERING'
            self.feedback(state, f'fire {fire_id}: aim on {source}, error '
                                 f'{np.linalg.norm(steer.error(target)):.2f} m, water {a.water_level:.2f} L')
            if a.water_empty():
                a.stop_pump()
                a.hold()                                # no velocity loop while we wait for the answers
                if not on_hole:
                    return False
                if not cold.seen_hot:
                    raise TaskError(f'fire {fire_id} {NOT_SEEN_HOT}: the tank ran dry on its hole, left active')
                out, self.dry_note = dry_tank_verdict(cold)
                a.backend.loginfo(f'[{self.name}] fire {fire_id}: tank dry, {self.dry_note}')
                return out
            watering = on_hole and pumping_since is not None and last_centred == now
            # water flowing into the hole now: is the fire still hot? Only then: off the hole the thermal
            # camera may not see the fire (seen: 6 "cold" answers while re-centring after a hole switch, fire
            # 10 % full), and cold answers while the wind holds the jet beside the hole leave a nearly quenched
            # fire unfinished (seen: 99.5 %). A hot answer counts from anywhere around the hole; a cold one
            # only with the jet on it now (centred on average, a gust may hold it beside the hole). Answers
            # that count come 0.5 s apart at least, each at the first control step the jet is on the hole
            # (asked at fixed beats, answers alias with a gust's sway and may all fall beside the hole), and
            # the camera is asked at least every ASK_PERIOD s wherever the jet is (a hot answer restarts the row)
            on_hole_now = ctl.centred(target)
            if watering and (on_hole_now and now - last_check >= 0.5 or now - last_ask >= ASK_PERIOD):
                last_ask = now
                hot = a.fire_detected()
                if hot or on_hole_now:
                    last_check = now
                    if cold.update(hot, flow is not None and flow.flowing(now)):
                        return True                     # cold: stop pumping, keep the rest of the tank
            if watering and not cold.seen_hot:
                unseen_water += step
                if unseen_water >= a.p.top_up_time:
                    raise TaskError(
                        f'fire {fire_id} {NOT_SEEN_HOT}: {unseen_water:.0f} s of water on its hole '
                        f'({"seen through" if self.locked_open else "not seen through"}) without a hot answer '
                        'there; left active')
            a.backend.sleep(1.0 / C.CONTROL_RATE_HZ)
