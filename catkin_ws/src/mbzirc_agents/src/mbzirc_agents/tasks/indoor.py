"""Indoor tasks (UAV and UGV): enter_building, search_indoor, extinguish_indoor_fire.

Indoors there is no room for the regions' planning around the building: moves are straight legs of
the sub-task `move` (UAV: a straight go_to; UGV: a straight drive), given by the caller's path.
"""
from __future__ import annotations

import math
from typing import NamedTuple, Optional

import numpy as np
from mbzirc_arena.yaw import wrap_angle
from rospy.numpy_msg import numpy_msg
from std_msgs.msg import Float64MultiArray

from .. import constants as C
from ..agent_task import AgentTask, TaskError
from ..geometry import facing_pose
from ..leg_guard import LegGuard, leg_blocked
from ..wall_clearance import off_the_walls, stop_short, wall_ahead, wall_normal_at
from .cold_check import NOT_SEEN_HOT, ColdConfirmation, Soak, WaterFlow, dry_tank_verdict
from .common import fire_position, floor_of, parse_fire, parse_floor, parse_path, parse_pose
from .explore import Exploration, footprint_here
from .passage import LaserPassage, crosses_outline
from .sensing import SensedObjects
from .thermal_contrast import FireContrast, pixel_bearing

TOP_UP_MIN_UPDATES = 20    # detections of a track before a cold fire there is topped up
WATERING_POSE_TOLERANCE = 0.5   # m: farther from where it saw the fire hot, the robot looks elsewhere
BLOCKED_WATERING_SLACK = 1.5   # m beyond ~indoor_fire_distance from the estimate a blocked approach waters from
AIM_TRIES = 6              # turns (and climbs) to the hot spot before pumping, each measured on a new image
AIM_SIGHTING_WAIT = 1.5    # s for a thermal detection taken after a turn
AIM_TURN_TIME = 3.0        # s at most for a turn to the hot spot
AIM_MAX_AGE = 0.5          # s: an older detection no longer turns the robot while it pumps
RAW_TURN_SETTLE = 0.5      # s after a turn on the raw image before a frame may turn the robot again
WATER_PERIOD = 0.5         # s of one round of the watering loop (feedback, wall checks, a hot/cold answer)
STEER_PERIOD = 0.1         # s between two corrections of the aim while pumping (`_steer_for`)
FROZEN_HEIGHT_STEP = 0.02  # m: a frozen aim's height set-point is re-sent when it moved this much
RAW_THERMAL_TOPIC = 'teraranger_evo_thermal/raw_temp_array'   # the thermal camera's 32 x 32 deg C
LOOK_TURN = 0.5            # rad of a look beside the heading for a fire out of view (the 33 deg view overlaps)
LOOK_CLIMB = 0.5           # m of a UAV's look above and below the watering height for it
LOOK_MIN_RISE = 5.0        # x ~out_contrast a warm area found beside the watering pose's view stands over its wall
LOOK_MAX_OFF = 1.5         # m from the fire's estimate where the laser may place a warm area found beside the view
LOOK_RAY_HALF_WIDTH = 0.15  # m either side of a warm area's bearing where the laser's returns place it ...
LOOK_RAY_REACH = 30.0      # m ... up to this far
LOOK_RAY_CORE = 0.05       # m either side of the bearing itself: the surface the warm area is on ...
LOOK_RAY_CORE_ANGLE = math.radians(1.5)   # ... (or this angle either side: a few beams of a 720-beam laser far off)
LOOK_EDGE_DEPTH = 0.5      # m ... no further than this beyond the corridor's nearest return (else an edge)
STANDOFF_SLACK = 0.25      # m nearer than ~indoor_fire_distance to the wall ahead before a UAV steps back to it


class Sighting(NamedTuple):
    """Where the thermal camera saw the fire in one image, and the pose it was taken from (pose_at)."""
    bearing: float   # rad of the hot spot off the heading the image was taken with
    yaw: float       # that heading
    rise: float      # m the hot spot lies above the camera's optical axis (body frame z)
    z: float         # the (GNSS) height the image was taken at


def gen_enter_building(goal, agent) -> dict:
    """EnterBuilding goal -> userdata: floor 1..2 (UAVs enter through windows), entry pose outside."""
    floor = parse_floor(goal.floor, (1, 2))
    pos, yaw = parse_pose(goal.entry, agent, 'entry')
    if yaw is None:
        raise ValueError('entry needs an orientation (the direction to fly in)')
    return {'floor': floor, 'entry': (pos, yaw)}


def gen_search_indoor_uav(goal, agent) -> dict:
    """UAV SearchIndoor goal: floor 1..2 and a non-empty path inside."""
    path = parse_path(goal.path, agent)
    if not path:
        raise ValueError('empty path: the UAV needs the waypoints to search')
    return {'floor': parse_floor(goal.floor, (1, 2)), 'path': path}


def gen_search_indoor_ugv(goal, agent) -> dict:
    """UGV SearchIndoor goal: floor 0 only; path optional (default: through the door)."""
    return {'floor': parse_floor(goal.floor, (0,)), 'path': parse_path(goal.path, agent)}


def gen_indoor_fire(goal, agent) -> dict:
    """A goal naming an indoor fire."""
    return {'fire_id': parse_fire(goal.fire_id, agent, (C.SUBTYPE_INDOOR,))}


class EnterBuilding(AgentTask):
    """Fly to the entry pose outside a window, then ~entry_depth m ahead through it: centred on the window
    the laser sees (tasks/passage.py; the entry pose carries the GNSS error)."""
    INPUT_KEYS = ['floor', 'entry']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.passage = LaserPassage(self)

    def run(self, ud) -> str:
        (pos, yaw) = ud.entry
        self.feedback('APPROACHING', f'to the window of floor {ud.floor}')
        self.call_task_or_raise('go_to', {'waypoint': (pos, yaw)})
        self.agent.wait_for_indoor_pose(self, f'the window of floor {ud.floor}')
        self.feedback('ENTERING', 'through the window')
        self.passage.ahead(yaw, self.agent.p.entry_depth)
        self.result['message'] = f'inside floor {ud.floor}'
        return C.SUCCESS


class SearchIndoor(AgentTask):
    """Follow the path inside; look with the thermal camera at each waypoint.

    A waypoint with an orientation is a viewpoint: the robot looks that way for `~check_fire_time`. One
    without (an all-zero quaternion) makes it turn on the spot and look along the four wall directions.
    A leg that crosses the building's outline (in or out through a window or the door), or an interior
    wall through a doorway the laser sees on it, is passed guided by the laser (tasks/passage.py).
    """
    INPUT_KEYS = ['floor', 'path']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.passage = LaserPassage(self)
        self.scans = LegGuard(self)          # its laser scans, for ~indoor_search explore (tasks/explore.py)

    def run(self, ud) -> str:
        a = self.agent
        path = list(ud.path) or self.default_path()
        found: list = []
        explore_here = False
        for i, (wp, yaw) in enumerate(path):
            self.feedback('MOVING', f'waypoint {i + 1}/{len(path)}')
            try:
                if crosses_outline(a.position(), wp):
                    self.passage.to(wp)
                else:
                    on_to = self.passage.doorway(wp)     # through a doorway on the way, if there is one
                    self.call_task_or_raise('move', {'waypoint': (on_to, yaw)})
            except TaskError as e:
                if a.p.indoor_search == 'explore' and footprint_here(a.position()) is not None:
                    # a leg of the path stopped inside (an interior wall no one was told of): explore from here
                    a.backend.logwarn(f'[{self.name}] waypoint {i + 1}: {e}: exploring from here')
                    explore_here = True
                    break
                raise TaskError(f'waypoint {i + 1}: {e}')
            found = self._look(ud.floor, i, len(path), yaw)
            if found and a.p.stop_at_first_fire:
                break
        if not found and a.p.indoor_search == 'explore' and (explore_here or path[-1][1] is None):
            found = Exploration(self, ud.floor).run()   # a last waypoint without heading: explore from it
        self.result['fire_ids'] = found
        self.result['message'] = (f'active indoor fires on floor {ud.floor}: {found}' if found
                                  else f'no indoor fire found on floor {ud.floor}')
        return C.SUCCESS

    def default_path(self) -> list:
        """The path to search when the goal gives none (the UGV's: through the door)."""
        raise TaskError('no path given')

    def _fires(self, floor: int) -> list:
        return [int(o.id) for o in self.agent.fires((C.SUBTYPE_INDOOR,)) if floor_of(o.pose.pose.position.z) == floor]

    def _look(self, floor: int, i: int, n: int, yaw) -> list:
        a = self.agent
        p = a.position()
        if yaw is not None:
            yaws, each = [yaw], a.p.check_fire_time
        else:
            base = round(p[3] / (math.pi / 2)) * (math.pi / 2)   # the walls are axis-aligned
            yaws, each = [base + k * math.pi / 2 for k in range(4)], 2.0
        for k, y in enumerate(yaws):
            self.feedback('LOOKING', f'waypoint {i + 1}/{n}: looking {k + 1}/{len(yaws)}')
            p = self._off_the_walls(p)
            a.move_to(self, p[:3], y, 'turning')
            found = self._look_once(floor, each)
            if found:
                return found
        return []

    def _off_the_walls(self, p):
        """p, or the place off the walls the laser sees nearer than ~min_wall_clearance (a UAV, indoors).
        Why (realistic seed 108): UAV 2 looking around at room 0's first waypoint hit facade B's inner face 5 s
        after arriving, its GNSS error growing towards the facade; each heading of a look holds ~2-4 s."""
        a = self.agent
        if a.ROBOT_TYPE != 'uav' or not a.p.wall_clearance or footprint_here(a.position()) is None:
            return p
        here = a.position()
        to = off_the_walls(self.scans.points(), here, a.p.min_wall_clearance, a.p.wall_clearance_margin)
        if to is None:
            return p
        a.backend.logwarn(f'[{self.name}] looking: a wall nearer than {a.p.min_wall_clearance:.2f} m by the laser: '
                          f'backing off {math.dist(to[:2], here[:2]):.2f} m')
        return (*to, p[3])

    def _look_once(self, floor: int, seconds: float) -> list:
        """One look the way the robot faces: the floor's fire ids once the estimator has a track of a fire
        the thermal camera saw hot (waiting up to ~confirm_time for it); none after a cold look.
        Rule: a search reports only fires it saw hot, so that its result means "burning, seen from this
        room": the central unit reaches a fire through the rooms that reported it, and takes a fire it
        doubted (not seen hot after water) as a target again when a search saw it hot."""
        if not self._hot(seconds):
            return []
        end = self.agent.backend.now() + self.agent.p.confirm_time
        while not self._fires(floor) and self.agent.backend.now() < end:
            self.sleep(0.25)
        return self._fires(floor)

    def _hot(self, seconds: float) -> bool:
        """Poll the thermal camera's frame filter for up to seconds (it needs > 1 s of hot frames).

        A look during which the detector never answered saw nothing: it goes on waiting for a first answer up
        to ~detector_wait s more (a detector starts after its agent on a loaded machine: 60-70 sim-s at 8x),
        then raises instead of reporting "no fire", so that the search fails (a UGV whose detector started
        late under load searched the whole ground floor blind and the floor's fire was never found)."""
        now = self.agent.backend.now
        end = now() + seconds
        deadline = end + self.agent.p.detector_wait
        answered = False
        while now() < end or (not answered and now() < deadline):
            self.sleep(0.25)
            hot = self.agent.fire_detected()
            answered = answered or hot is not None
            if hot:
                return True
        if not answered:
            raise TaskError('the thermal camera does not answer (thermal_detection/fire_detected): cannot search')
        return False


class ExtinguishIndoorFire(AgentTask):
    """Face the fire at ~indoor_fire_distance (from the side the robot is on), turn until the thermal hot
    spot is straight ahead, and pump until cold.

    Walls (wall_clearance.py, ~wall_clearance): before the approach the robot backs off any wall nearer than
    ~min_wall_clearance, a wall across the approach with a doorway (the fire in the next room) is passed
    through the doorway by the laser (passage.LaserPassage.doorway; not with ~explore_in_sight), the approach stops at ~indoor_fire_distance from the wall its laser sees ahead, and
    while the robot checks and pumps it backs off any wall nearer than ~min_wall_clearance. Why: the watering pose is placed on the fire's GNSS-frame estimate and held on the
    robot's own drifting GNSS fix (realistic seeds 104, 106: a UAV holding its watering pose on floor 2 hit
    the interior wall the fire is on).

    Aim (UAV): the height too is steered on the thermal image, so that the hot spot sits where the jet lands
    (~jet_rise above the optical axis): the watering height comes from the fire estimate and is held on the
    GNSS height, whose error (0.3-0.5 m, wandering) puts a jet of a few cm beside a 0.15 m hole (realistic
    seed 108: 2 L shot at each floor-1/2 fire, the fires left at 13-91 %).

    When it is out (tasks/cold_check.py): seen hot from the watering pose, watered until it reads cold and
    soaked (~soak_fraction) with water flowing at it (the tank level dropping), then, the pump off, cold
    C.COLD_CHECKS times in a row from that pose, cold judged on the raw thermal image
    (tasks/thermal_contrast.py: the locked fire no more than ~out_contrast above its wall, not the detector's
    silence), the jet's height on the hot spot as last seen (a UAV whose
    last sighting put the fire beyond the height it could reach waters on, but a cold answer then says "out
    of view", not "out"). A fire never seen hot from there is never reported out: the goal fails with why,
    and the central unit tries again or gives it to another robot."""
    INPUT_KEYS = ['fire_id']

    def __init__(self, name, agent, **args) -> None:
        super().__init__(name, agent, **args)
        self.sensed = SensedObjects(self)
        self.walls = LegGuard(self)                      # its laser scans (the wall clearance's returns)
        self.passage = LaserPassage(self)                # a doorway across the approach
        self.aim_z: Optional[float] = None               # the height held to aim (UAV), None: not steered yet
        self.watering_z: Optional[float] = None          # the height the watering pose was reached at
        self.fire_xy: Optional[np.ndarray] = None        # the fire's estimate of this run (x, y)
        self.hold_xy: Optional[np.ndarray] = None        # the x, y set-point a UAV holds there (None: UGV, not yet)
        self.on_jet = True                               # the last sighting's height correction was all sent
        self.frozen_true_z: Optional[float] = None       # the frozen aim's true height (altimeter), None: unfrozen
        self.raw_turn_time = -math.inf                    # when the frozen aim last turned on the raw image
        self.contrast = FireContrast(agent.backend.now, agent.p.out_contrast, agent.p.thermal_period)
        # subscribed only while the task runs: each frame of the trial deserialised for nothing otherwise
        self.iface.add_demand(self.name, RAW_THERMAL_TOPIC, numpy_msg(Float64MultiArray),
                              lambda msg: self.contrast.on_frame(msg.data))

    def _wall_points(self) -> Optional[np.ndarray]:
        """The laser's returns for the wall clearance; None when it is off or without a fresh scan (said)."""
        a = self.agent
        if not a.p.wall_clearance:
            return None
        points = self.walls.points()
        if points is None:
            a.backend.logerr_throttle(5.0, f'[{self.name}] wall clearance: no fresh laser scan, the distance to '
                                            'the walls is unchecked')
        return points

    def _laser_standoff(self, pos: tuple) -> tuple:
        """The watering position pos, moved back along the approach to ~indoor_fire_distance from the wall the
        laser sees ahead when the GNSS estimate puts it nearer."""
        a = self.agent
        points = self._wall_points()
        if points is None:
            return pos
        here = a.position()
        short = stop_short(points, here, pos, a.p.leg_guard_half_width, a.p.indoor_fire_distance)
        if short is None:
            return pos
        a.backend.loginfo(f'[{self.name}] watering pose stops {math.dist(short, pos[:2]):.2f} m short of its '
                          f'GNSS estimate: {a.p.indoor_fire_distance:.2f} m from the wall the laser sees ahead')
        return (float(short[0]), float(short[1]), pos[2])

    def _keep_off_walls(self, yaw: float) -> Optional[np.ndarray]:
        """Back off (heading yaw) from walls nearer than ~min_wall_clearance by the laser; the x, y, z sent,
        None when the robot is clear (or unchecked)."""
        a = self.agent
        here = a.position()
        off = off_the_walls(self._wall_points(), here, a.p.min_wall_clearance, a.p.wall_clearance_margin)
        if off is None:
            return None
        to = np.array([off[0], off[1], self._held_z(here)])
        a.send_waypoint(to[0], to[1], to[2], yaw)
        if self.hold_xy is not None:
            self.hold_xy = to[:2].copy()
        a.backend.loginfo_throttle(2.0, f'[{self.name}] a wall nearer than {a.p.min_wall_clearance:.2f} m by '
                                        f'the laser: backing off {math.dist(to[:2], here[:2]):.2f} m')
        return to

    def _keep_watering_distance(self, yaw: float) -> Optional[np.ndarray]:
        """While watering (UAV): when the laser sees the wall ahead (along heading yaw) STANDOFF_SLACK m or more
        nearer than ~indoor_fire_distance, the held set-point steps back along the heading by the shortfall;
        the x, y, z sent, None when nothing moved. Along the heading only, so the jet's spot on the wall stays.
        Why (realistic seed 103, in1_e's first pour, truth from the run's bag): the GNSS error drifted 0.7 m
        along the wall's normal and took the UAV from 1.5 to 1.0-1.2 m from the wall, where the ring of flames
        fills the view and the image no longer shows the hole whole (thermal_contrast.warm_spot): the aim no
        longer followed it, the jet went 0.2-0.3 m beside and below the hole and the fire stayed at 71 % while
        the tank ran dry; the wall back-off (`_keep_off_walls`) acts only within ~min_wall_clearance."""
        a = self.agent
        if self.hold_xy is None:
            return None
        points = self._wall_points()
        if points is None:
            return None
        here = a.position()
        u = np.array([math.cos(yaw), math.sin(yaw)])
        want = a.p.indoor_fire_distance
        wall = wall_ahead(points, here, u, a.p.leg_guard_half_width, want)
        if wall is None or wall > want - STANDOFF_SLACK:
            return None
        self.hold_xy = self.hold_xy - u * (want - wall)
        to = np.array([self.hold_xy[0], self.hold_xy[1], self._held_z(here)])
        a.send_waypoint(to[0], to[1], to[2], yaw)
        a.backend.loginfo_throttle(2.0, f'[{self.name}] the wall ahead {wall:.2f} m away by the laser: stepping '
                                        f'back {want - wall:.2f} m to {want:.2f} m from it')
        return to

    def _clear_of_walls_first(self) -> None:
        """Before the approach: back off any wall the laser sees nearer than ~min_wall_clearance, and wait (up
        to AIM_TURN_TIME s) until the robot is there. Why (realistic seed 103): two UAVs that a search left
        0.3 m from facade B's inside face (their GNSS fix 1.3 m off) hit it on the first leg of the approach;
        the wall beside them also read as the wall "ahead" of the leg (`_laser_standoff`), which put the
        watering pose 2.2 m short, behind them, along that wall."""
        a = self.agent
        to = self._keep_off_walls(a.position()[3])
        if to is None:
            return
        end = a.backend.now() + AIM_TURN_TIME
        while a.backend.now() < end and math.dist(a.position()[:2], to[:2]) > WATERING_POSE_TOLERANCE / 2:
            self.sleep(0.1)

    def _sighted(self, since: float, wait: float) -> Optional[Sighting]:
        """The thermal camera's fire in a detection whose image was taken after `since`, waiting up to `wait`
        s for one; None without (or with a non-finite position)."""
        a = self.agent
        end = a.backend.now() + wait
        while True:
            fire, stamp = self.sensed.latest_fire()
            if fire is not None and stamp > since:
                rel = fire[1]
                bearing = math.atan2(rel[1], rel[0])
                if not (math.isfinite(bearing) and math.isfinite(rel[2])):
                    return None
                then = a.pose_at(stamp)
                return self._on_raw_image(Sighting(bearing, float(then[3]), float(rel[2]), float(then[2])),
                                          since, float(rel[0]))
            if a.backend.now() >= end:
                return None
            self.sleep(0.1)

    def _on_raw_image(self, seen: Sighting, since: float, distance: float) -> Sighting:
        """The detector's sighting `seen` with its bearing and rise taken from the fire's centre in the raw
        thermal image (thermal_contrast.warm_spot: the hole when the ring of flames fills the frame) when a
        frame taken after `since` shows it whole (not a fire cut by the frame's edge); `distance` (m, the
        detector's range to the wall) turns its row into a rise. Why: the detector places the fire at the
        centroid of its hot contours, and from the watering distance the ring of flames is as wide as the
        view: clipped by the frame's edges, that centroid stays near the image centre (ual_sim's realistic
        world: a fire 6 deg off the heading read 3.9 deg off at 1.5 m, 1.4 deg at 1.2 m, none at 1.0 m), so
        the aim stopped short of the hole while the wandering GNSS fix took the UAV sideways."""
        spot = self.contrast.warm_spot()
        if spot is None or not spot.whole or spot.time <= since or not math.isfinite(distance):
            return seen
        fov = self.agent.p.forward_camera_fov
        then = self.agent.pose_at(spot.time)
        rise = distance * math.tan(pixel_bearing(spot.row, fov))
        return Sighting(pixel_bearing(spot.column, fov), float(then[3]), rise, float(then[2]))

    def _height_target(self, seen: Sighting) -> Optional[float]:
        """The height that puts the hot spot where the jet lands, None when it is there already (within
        ~aim_height_tolerance) or the robot cannot climb (UGV). Relative to the height the image was taken
        at, so that it holds for any GNSS height error (a bias moves both alike); each correction at most
        ~aim_height_step, all within ~aim_height_range of the watering height. Sets on_jet: the whole
        correction this sighting asks for was sent (else the jet is still off the hot spot)."""
        a = self.agent
        if a.ROBOT_TYPE != 'uav' or self.watering_z is None:
            return None
        error = seen.rise - a.p.jet_rise
        if abs(error) < a.p.aim_height_tolerance:
            self.on_jet = True
            return None
        step = max(-a.p.aim_height_step, min(a.p.aim_height_step, error))
        reach = a.p.aim_height_range
        target = max(self.watering_z - reach, min(self.watering_z + reach, seen.z + step))
        self.on_jet = abs(seen.z + error - target) < a.p.aim_height_tolerance
        held = self._held_z(a.position())
        return None if abs(target - held) < 1e-3 else target

    def _correct_aim(self, seen: Sighting, yaw: float) -> Optional[float]:
        """The heading to aim at from sighting `seen` (heading yaw held now), with aim_z set to the height
        to hold; None when both are on the hot spot already (nothing to send)."""
        turn = abs(seen.bearing) >= self.agent.p.aim_bearing_tolerance
        z = self._height_target(seen)
        if not turn and z is None:
            return None
        if z is not None:
            self.aim_z = z
        return seen.yaw + seen.bearing if turn else yaw

    def _held_z(self, here) -> float:
        """The height set-point to hold: the aimed one once steered, else where the robot is."""
        return float(here[2]) if self.aim_z is None else self.aim_z

    def _face_the_heat(self, yaw: float, tries: int = AIM_TRIES) -> Optional[float]:
        """Turn (from heading yaw) until the thermal camera's fire is straight ahead (within
        ~aim_bearing_tolerance) and, for a UAV, climb or sink until it sits where the jet lands
        (_height_target); the heading it aimed to, None when it did not move. Why: there is no hole to aim
        at indoors, and the pose the fire estimate was faced from carries the GNSS error; the jet leaves
        along the heading (seen under realistic uncertainty: 2 L pumped beside an indoor fire, 18 % of it in).

        Closed loop: each turn is measured again on an image taken after it (the bearing of a 32-pixel
        image's hot spot is approximate, and one taken while the robot still turned belongs to another
        heading: realistic seed 103, a single turn left the UGV's jet 0.14 m beside the hole, 4 degrees)."""
        a = self.agent
        aimed = None
        since = a.backend.now() - 1.0
        for _ in range(tries):
            seen = self._sighted(since, AIM_SIGHTING_WAIT)
            new_yaw = None if seen is None else self._correct_aim(seen, yaw)
            if new_yaw is None:
                break
            aimed = yaw = self._turn_to(new_yaw)
            since = a.backend.now()                      # only images of the new aim count
        return aimed

    def _turn_to(self, yaw: float) -> float:
        """Turn where it stands to heading yaw, at the held height (no translation: the robot stays where it
        sees the fire from), and wait until it points there at that height (at most AIM_TURN_TIME s)."""
        a = self.agent
        p = self._turn_in_place(yaw)
        z = self._held_z(p)
        self.feedback('AIMING', f'turning {math.degrees(wrap_angle(yaw - p[3])):.0f} deg, {z - p[2]:+.2f} m up '
                                'to the hot spot')
        end = a.backend.now() + AIM_TURN_TIME
        while a.backend.now() < end:
            here = a.position()
            level = self.aim_z is None or abs(here[2] - z) <= a.p.aim_height_tolerance   # (fix noise: not /2)
            if abs(wrap_angle(here[3] - yaw)) <= a.p.aim_bearing_tolerance / 2 and level:
                break
            self._wait_off_walls(0.1, yaw)
        return yaw

    def _wait_off_walls(self, seconds: float, yaw: float) -> None:
        """Sleep, then back off (heading yaw) from walls the laser sees nearer than ~min_wall_clearance. Every
        wait at a watering pose keeps off the walls this way, as the watering does: the UAL holds the GNSS
        set-point, and the robot's true place drifts with the GNSS error (realistic seed 108: UAV 2 hit the
        wall it faced while looking beside, above and below the watering pose, ~25 s, its error moving ~1 m)."""
        self.sleep(seconds)
        self._keep_off_walls(yaw)

    def _look_around(self, yaw: float) -> Optional[float]:
        """The fire not in sight from the watering pose (heading yaw): look for it in the raw thermal image
        (thermal_contrast.warm_spot) straight ahead, then LOOK_TURN rad to either side and (UAV) LOOK_CLIMB m
        above and below (and, none showing, twice that), each on a frame taken after the robot got there. A
        look where the fire detector reports a fire ends the search there; else, once every look was made, the warmest area seen is
        taken; turn (and climb) onto its centre and return that heading. None, back at yaw and the height it
        came at, when none shows. Why (realistic seed 103): the watering pose faces the fire's track from
        where the robot's GNSS fix says it is, and the two GNSS errors (0.5 m per axis, 0.4 m in height,
        each) differ by more than the view's half-width plus the ring of flames at the watering distance
        (~0.85 m) in a fair share of approaches: a UAV sent to top up a fire burning at 0 % read it cold from
        there, detector and raw image, and pumped 1.27 L beside it. A warm area counts here only when it
        stands LOOK_MIN_RISE x ~out_contrast over its wall: a fainter one beside the view is not told from a
        wall's warm feature (realistic seed 105: a 5 degC area 43 deg off the heading took a top-up's whole
        tank, the fire at 98 % untouched). Why the warmest and not the first: a sun-heated outer wall seen
        from inside stands 5-25 degC over the interior walls, and the first look that showed one took the
        tank (closed loop, bench_indoor_pour.py --track-from 3, seed 12: three whole tanks 1.6 m beside
        fires that a look 29 deg further showed burning; ual_sim's realistic profile)."""
        a = self.agent
        z0 = self._held_z(a.position())
        looks = [(0.0, 0.0), (LOOK_TURN, 0.0), (-LOOK_TURN, 0.0)]
        if a.ROBOT_TYPE == 'uav':
            looks += [(0.0, LOOK_CLIMB), (0.0, -LOOK_CLIMB)]
        best = self._looks(yaw, z0, looks, 'fire not in sight', warm_too=True)
        if best is None and a.ROBOT_TYPE == 'uav':
            # farther up and down: the track's height and this UAV's are true heights by two altimeters'
            # estimates, and a robot without a fresh estimate places and flies GNSS heights, whose vertical
            # errors differ by up to a metre (explore + GNSS-denied seed 109 on 61430b6: in1_w's track 0.78 m
            # above the fire, a top-up's five looks found nothing and its 1.34 L went onto the wall, the fire
            # left at 93 %)
            best = self._looks(yaw, z0, [(0.0, 2 * LOOK_CLIMB), (0.0, -2 * LOOK_CLIMB)], 'fire not in sight',
                               warm_too=True)
        if best is None:
            a.backend.loginfo(f'[{self.name}] fire not in sight from the watering pose nor beside, above or '
                              'below it')
            self._back_to(yaw, z0)
            return None
        spot, then = best[1], best[2]
        fov = a.p.forward_camera_fov
        new_yaw = float(then[3]) + pixel_bearing(spot.column, fov)
        if a.ROBOT_TYPE == 'uav':
            rise = a.p.indoor_fire_distance * math.tan(pixel_bearing(spot.row, fov)) - a.p.jet_rise
            reach = a.p.aim_height_range
            self.aim_z = max(z0 - reach, min(z0 + reach, float(then[2]) + rise))
        why = ('the fire detector\'s fire' if math.isinf(best[0][1]) else
               f'a ring of flames, {spot.contrast:.1f} degC over its wall,' if spot.ringed else
               f'the warmest area, {spot.contrast:.1f} degC over its wall,')
        a.backend.loginfo(f'[{self.name}] fire not in sight from the watering pose: {why} '
                          f'{math.degrees(wrap_angle(new_yaw - yaw)):+.0f} deg off the heading, '
                          f'{self._held_z(then) - z0:+.2f} m up: turning onto it')
        return self._turn_to(new_yaw)

    def _looks(self, yaw: float, z0: float, looks: list, why: str, warm_too: bool) -> Optional[tuple]:
        """(rank, spot, the pose its frame was taken from) of the likeliest fire seen in the looks [(turn rad,
        climb m)] from heading yaw and height z0, each on a frame taken there: a spot while the detector reports a fire ends them ((True, inf)), else a ring of flames
        (`ringed_spot`, LOCK_MIN_RISE x ~out_contrast over its wall) or, warm_too, an area LOOK_MIN_RISE x
        ~out_contrast over its wall, ranked ringed first, then by contrast; None when none showed. The robot is
        left at the last look's heading and height."""
        a = self.agent
        best = None
        for turn, climb in looks:
            if turn or climb:
                self.feedback('LOOKING', f'{why}: looking {math.degrees(turn):+.0f} deg, {climb:+.1f} m')
                self.aim_z = z0 + climb if a.ROBOT_TYPE == 'uav' else None
                self._turn_to(yaw + turn)
            since = a.backend.now()
            spot, end = None, since + AIM_SIGHTING_WAIT
            while a.backend.now() < end:
                ring = self.contrast.warm_spot(ringed=True)
                warm = self.contrast.warm_spot(LOOK_MIN_RISE) if warm_too else None
                spot = next((s for s in (ring, warm) if s is not None and s.time > since), None)
                if spot is not None:
                    break
                self._wait_off_walls(0.1, yaw + turn)
            if spot is None:
                continue
            # the pose its frame was taken from, now: the pose history holds a few seconds only, and the looks
            # take ten (ideal seed 7 at RTF 4: the fire's ring straight ahead, placed by the pose history's
            # oldest pose, from the look 29 deg aside, drew 5 tanks 0.6 m beside it)
            then = a.pose_at(spot.time)
            if self.sensed.latest_fire()[1] > since:     # the detector's fire: no wall passes its test
                return (True, math.inf), spot, then
            off = self._off_the_fire(spot, then)
            if off is not None:
                a.backend.loginfo(f'[{self.name}] {why}: a warm area {spot.contrast:.1f} degC over its wall, {off}: '
                                  'not the fire')
                continue
            rank = (spot.ringed, spot.contrast)
            if best is None or rank > best[0]:
                best = (rank, spot, then)
        return best

    def _off_the_fire(self, spot, then) -> Optional[str]:
        """Why the laser places a thermal spot (seen from pose `then`) where the fire cannot be, or None: the
        wall along its bearing (wall_clearance.wall_ahead, in a corridor LOOK_RAY_HALF_WIDTH either side)
        lies beyond LOOK_MAX_OFF from the fire's estimate, or there is none (an opening), or the bearing itself
        (LOOK_RAY_CORE either side) passes that return's edge (more than LOOK_EDGE_DEPTH further). Unchecked (None)
        without a fresh scan or an estimate. Why (explore + GNSS-denied seed 106): in1_w, 98 % out and too faint to see, stands beside a window; four top-ups each took the
        warmest area in their looks, 33 deg off, the sun-heated outside seen through the window, and poured
        their whole tank there."""
        points = self.walls.points()
        if points is None or self.fire_xy is None:
            return None
        bearing = float(then[3]) + pixel_bearing(spot.column, self.agent.p.forward_camera_fov)
        u = (math.cos(bearing), math.sin(bearing))
        r = wall_ahead(points, then[:2], u, LOOK_RAY_HALF_WIDTH, LOOK_RAY_REACH)
        if r is None:
            return 'no laser return along it (an opening)'
        # the corridor's nearest return may be a window's jamb or a wall's corner beside the bearing, with the
        # heat seen past it (explore + GNSS-denied seed 109 on fb42812: in1_w, 98.7 % out beside a window, two
        # top-ups turned 45 deg onto the warm outside past the window's jamb 0.1 m from their bearing and
        # poured a tank each there): the bearing itself must meet that surface
        core = wall_ahead(points, then[:2], u, max(LOOK_RAY_CORE, r * LOOK_RAY_CORE_ANGLE), LOOK_RAY_REACH)
        if core is None or core > r + LOOK_EDGE_DEPTH:
            return (f'past an edge {r:.1f} m away (its bearing meets ' +
                    ('no return)' if core is None else f'a surface at {core:.1f} m)'))
        place = np.array(then[:2], dtype=float) + r * np.array([math.cos(bearing), math.sin(bearing)])
        off = float(np.linalg.norm(place - self.fire_xy))
        if off > LOOK_MAX_OFF:
            return f'placed by the laser {off:.1f} m from the fire\'s estimate (> {LOOK_MAX_OFF:.1f} m)'
        return None

    def _back_to(self, yaw: float, z0: float) -> None:
        """Back at heading yaw and (UAV) the height z0 it looked from, where it stands."""
        self.aim_z = z0 if self.agent.ROBOT_TYPE == 'uav' else None
        self._turn_to(yaw)

    def _still_burning_beside(self, yaw: float) -> Optional[str]:
        """After the cold answers, from the watering pose (heading yaw): a look LOOK_TURN rad to either side for
        the fire the cold answers may have looked past; why it is not out (the detector's fire or a ring of
        flames there), None when neither shows. The robot turns back to yaw.
        Why (realistic seed 107 on 52c0d45): a top-up locked on a warm area 17 deg off its heading, the aim then
        drifted off it, the locked pixels and the whole view read at the wall's level within 1.2 s, and the
        fire, 0.87 full and 26 degC over its wall beside the view, was reported out: nothing in view is what
        a fire out and a fire out of view both look like."""
        a = self.agent
        z0 = self._held_z(a.position())
        seen = self._looks(yaw, z0, [(LOOK_TURN, 0.0), (-LOOK_TURN, 0.0)], 'checking beside the fire', warm_too=False)
        self._back_to(yaw, z0)
        if seen is None:
            return None
        rank, spot, _ = seen
        what = 'the fire detector\'s fire' if math.isinf(rank[1]) else f'a ring of flames {spot.contrast:.1f} degC over its wall'
        return f'{what} beside the watering pose after the cold answers: not judged out, left active'

    def _turn_in_place(self, yaw: float):
        """Hold where the robot is (at the held height), heading yaw; the pose it was at. No translation: a
        drive to a GNSS position moves the robot by its GNSS error's drift, off where it sees the fire from.
        A UAV keeps the x, y set-point it holds (hold_xy: the watering pose's, moved only by a wall back-off),
        a UGV (no position hold) is told where it stands. Why not a UAV's fix of the moment: gusts push it
        +-0.2-0.3 m about its set-point within a second (realistic seed 104, floor 1), and each turn of the
        aim or re-sent height of a frozen aim made that push the new set-point: the set-point walked 0.6 m in
        a pour of 14 turns, the jet 0.2-0.4 m beside the hole for much of it (seed 108: "0.96 m off the
        watering pose" when the fire went out, so it was not judged out)."""
        p = self.agent.position()
        x, y = (p[0], p[1]) if self.hold_xy is None else self.hold_xy
        self.agent.send_waypoint(x, y, self._held_z(p), yaw)
        return p

    def run(self, ud) -> str:
        a = self.agent
        if a.water_empty():
            raise TaskError('tank empty')
        fire = np.array(fire_position(a, ud.fire_id))
        if a.ROBOT_TYPE == 'uav':      # a track's height is a true one (UavAgent._detectors_pose): flown as such
            fire[2] = a.at_true_height(fire)[2]
        self.fire_xy = fire[:2].copy()
        self.sensed.clear()                              # a previous run's detections aim nothing
        self.contrast.clear()                            # nor its locked fire
        self.aim_z, self.watering_z, self.on_jet, self.hold_xy = None, None, True, None
        self._clear_of_walls_first()
        here = a.position()
        frm = (here[0], here[1], fire[2] if a.ROBOT_TYPE == 'uav' else here[2])
        normal = wall_normal_at(self._wall_points(), fire, here)
        if normal is not None:                           # square to the fire's wall, on the robot's side
            frm = (fire[0] + normal[0], fire[1] + normal[1], frm[2])
        pos, yaw = facing_pose(fire, frm, a.p.indoor_fire_distance)
        # a wall with a doorway across the way (the fire in the next room): through the doorway first, and the
        # standoff measured from there (c3_floor_plan_b seed 101: the UGV's straight approach from the south
        # strip met the strip's wall three times, the guard held it, the fire was given up). Not in-sight
        # explorers (the UAVs): they water only fires in sight of where they came in, and pass no doorway
        if not a.p.explore_in_sight:
            pos = tuple(self.passage.doorway(pos))
        pos = self._laser_standoff(pos)
        self.feedback('APPROACHING', f'facing fire {ud.fire_id}')
        yaw = self._approach(ud.fire_id, fire, pos, yaw)
        self.watering_z = float(a.position()[2])
        if a.ROBOT_TYPE == 'uav':
            self.hold_xy = np.array(pos[:2], dtype=float)   # the move's set-point, held by the UAL
        self.feedback('CHECKING', f'fire {ud.fire_id}: is it in sight of the thermal camera?')
        cold = ColdConfirmation()
        seen = self._seen_hot(cold, a.p.check_fire_time)
        if not seen:
            found = self._look_around(yaw)
            if found is not None:
                yaw = found
                seen = self._seen_hot(cold, a.p.check_fire_time)
        if seen:
            turned = self._face_the_heat(yaw)
            if turned is not None:                      # a new heading: seen hot from there, or no water
                yaw = turned
                cold = ColdConfirmation()
                if not self._seen_hot(cold, a.p.check_fire_time, raw_too=True):
                    raise TaskError(f'fire {ud.fire_id} {NOT_SEEN_HOT}: hot before aiming at its hot spot, '
                                    'cold after; no water spent')
        elif not self._well_localised(ud.fire_id):
            raise TaskError(f'fire {ud.fire_id} not in sight of the thermal camera: no water spent')
        out, why, yaw = self._water(ud.fire_id, cold, yaw)
        if out:
            beside = self._still_burning_beside(yaw)
            if beside is not None:
                a.backend.logwarn(f'[{self.name}] fire {ud.fire_id}: {beside}')
                out, why = False, beside
        if out:
            a.set_object_status(ud.fire_id, C.STATUS_EXTINGUISHED)
        water = a.water_level if math.isfinite(a.water_level) else 0.0
        self.result.update(extinguished=out, water_left=max(0.0, water), message=f'fire {ud.fire_id} {why}')
        return C.SUCCESS

    def _approach(self, fire_id: int, fire: np.ndarray, pos: tuple, yaw: float) -> float:
        """To the watering pose pos facing yaw; the heading to water from. A leg the laser finds blocked within
        ~indoor_fire_distance + BLOCKED_WATERING_SLACK of the fire's estimate leaves the robot watering from
        where it stopped, facing the estimate (the check, look-around and aim on the thermal image follow):
        the wall that blocked it is the fire's, or a corner beside it. Why (explore + GNSS-denied seed 102): a
        UGV's estimate of a fire 0.75 m behind the wall it burns on (seen on SLAM while its pose was off) put
        the watering pose 0.2 m from the wall; the guard stopped the leg 1 m from the wall three times, and
        the robot gave the fire up."""
        a = self.agent
        try:
            self.call_task_or_raise('move', {'waypoint': (pos, yaw)})
            return yaw
        except TaskError as e:
            here = a.position()
            near = math.dist(here[:2], fire[:2]) <= a.p.indoor_fire_distance + BLOCKED_WATERING_SLACK
            if not (leg_blocked(e) and near):
                raise
            to_fire = math.atan2(fire[1] - here[1], fire[0] - here[0])
            a.backend.logwarn(f'[{self.name}] fire {fire_id}: the approach stopped {math.dist(here[:2], fire[:2]):.1f} '
                              f'm from its estimate ({e}): watering from here')
            a.move_to(self, here[:3], to_fire, 'turning to the fire')
            return to_fire

    def _water(self, fire_id: int, cold: ColdConfirmation, yaw: float) -> tuple:
        """Pump from here, facing yaw (the watering pose: where the fire was checked from), until the fire
        is judged out or the tank is empty; (out, why, the heading the pour ended at).

        A fire not seen hot yet (a confirmed, well-localised track that reads cold) is topped up: it gets
        ~top_up_time of water in which to show hot. Why: a fire being filled cools down in the thermal
        image, so a fire left nearly full by a robot whose tank ran dry is invisible to the next one (seen
        in a mission: 94 % full, "not in sight" three times, never finished). Water can finish it; the
        verdict "out" cannot be given without seeing it (seen: a top-up from a pose that did not look at
        the fire marked a fire at 63 % out): the goal fails, the fire stays active.

        Until the soak is over, cold answers count only with water flowing (the tank level dropping) and the
        robot still at the watering pose. After it the pump is off and C.COLD_CHECKS cold answers in a row
        from the watering pose (the jet's aim on the fire) say "out"; a hot one starts the pump again (a new
        soak follows its next cold answer). Why the pump off: a fire that still burns shows its heat again
        once the water stops (under the jet its surface may read cold), and counting under the jet cost
        ~1.6 L of a 2 L tank in missions (6 answers, 0.2 L/s, answers ~1.3 sim-s apart at 8x): a fire
        needing more than its nominal litre ran the tank dry after it was out and stayed active for a
        top-up trip. The count costs time only (~3 s), so it stays at C.COLD_CHECKS.
        The heading stays on the hot spot the thermal camera sees (`_keep_aim`); turned off it, the robot
        turns back where it stands. It is never driven back to the pose's GNSS position: a
        robot holds its own set-point, and a drive to a GNSS position moves it by the drift of the GNSS
        error since (realistic seed 103: the UGV moved 0.37 m and its jet hit 0.5 m beside the hole).
        The one move it makes: backing off a wall its laser sees nearer than ~min_wall_clearance (a relative
        move from where it is; the watering pose moves with it).
        A pump that moves no water for
        cold_check.NO_FLOW_TIME fails the goal.

        Hot or cold (`_hot`): hot while the detector sees the fire, else the locked fire's contrast to its wall
        in the raw thermal image (tasks/thermal_contrast.py), cold at ~out_contrast. Once seen hot, the first
        cold answer starts a soak (cold_check.Soak: ~soak_fraction of the water that made the fire read cold,
        at least ~soak_min_time), and only then do cold answers count. While the detector no longer sees the
        fire the aim is frozen (`_freeze_aim`): nothing corrects the aim, and re-deriving it from GNSS moves
        the jet by the drift of the GNSS error.
        """
        a = self.agent
        pose = np.append(a.position()[:3], yaw)
        if self.hold_xy is not None:
            pose[:2] = self.hold_xy                      # a UAV's is its set-point (its fix wobbles about it)
        soak = Soak(a.p.soak_fraction, a.p.soak_min_time)
        frozen, first_level, pumped = False, None, 0.0
        dry_early = None                                 # share of the soak done when the tank ran dry, if too little
        self.frozen_true_z = None
        self.raw_turn_time = -math.inf
        try:
            a.start_pump()
            pumping = True
            start = a.backend.now()
            flow = WaterFlow(start)
            while not pumping or not a.water_empty() or soak.soaking:   # the pump-off confirmation needs no water
                if pumping and a.water_empty():          # dry while soaking: confirm what it has
                    a.stop_pump()
                    pumping = False
                    if first_level is not None and math.isfinite(a.water_level):
                        pumped = first_level - a.water_level     # all of it: the tank is dry now
                    share = soak.share_done(pumped)
                    if share < a.p.dry_soak_min_share:
                        dry_early = share
                        break
                    soak.done = True
                    cold.restart()
                    a.backend.loginfo(f'[{self.name}] fire {fire_id}: the tank ran dry while soaking it '
                                      f'({100 * share:.0f} % of the soak; it read cold with water flowing): out '
                                      f'once it reads cold {cold.checks} times in a row without water')
                self.check_preempt()
                now = a.backend.now()
                if now - start > a.p.extinguish_timeout:
                    raise TaskError('timeout while pumping')
                if not cold.seen_hot and now - start >= a.p.top_up_time:
                    raise TaskError(f'fire {fire_id} {NOT_SEEN_HOT}: {now - start:.0f} s of top-up water on '
                                    'its confirmed track, left active')
                stalled = flow.stalled(now, fire_id) if pumping else None
                if stalled:
                    raise TaskError(stalled)
                if not pumping:
                    self.feedback('CONFIRMING', f'fire {fire_id} soaked: pump off, watching it stay cold '
                                                f'({cold.cold_in_row}/{cold.checks}), water {a.water_level:.2f} L')
                elif soak.soaking:
                    self.feedback('SOAKING', f'fire {fire_id} reads cold: soaking it, aim frozen, water '
                                             f'{a.water_level:.2f} L')
                elif cold.seen_hot:
                    self.feedback('SHOOTING', f'fire {fire_id}: water {a.water_level:.2f} L')
                else:
                    self.feedback('TOPPING_UP', f'fire {fire_id} reads cold but was never put out: water '
                                                f'{a.water_level:.2f} L')
                pose[3] = self._steer_for(WATER_PERIOD, pose[3], frozen)
                if self.aim_z is not None:
                    pose[2] = self.aim_z                         # the watering pose climbs with the aim
                here = a.position()
                at_pose = self._at(pose, here)
                if not self._heading_at(pose, here):
                    self._turn_in_place(pose[3])                 # turned away: back, where it stands
                backed = self._keep_off_walls(pose[3])           # last: its set-point is the one held
                if backed is None:
                    backed = self._keep_watering_distance(pose[3])
                if backed is not None:
                    pose[:3] = backed                            # the watering pose moves with it
                looking = at_pose and self.on_jet                # where it saw the fire hot, the jet on it
                flowing = flow.update(a.water_level, a.backend.now())
                watered = (flowing or not pumping) and looking
                if first_level is None and math.isfinite(a.water_level):
                    first_level = a.water_level
                pumped = 0.0 if first_level is None or not math.isfinite(a.water_level) \
                    else first_level - a.water_level
                detected = a.fire_detected()
                hot = self._hot(detected, fire_id)
                if hot is False and not watered:
                    self._say_why_not_counted(fire_id, pose, here, flowing or not pumping)
                if cold.update(soak.update(hot, watered, pumped, a.backend.now()), watered):
                    break
                if pumping and soak.done:                    # soaked: confirm with the pump off
                    a.stop_pump()
                    pumping = False
                    cold.restart()
                    a.backend.loginfo(f'[{self.name}] fire {fire_id} soaked ({pumped:.2f} L): pump off, '
                                      f'out once it reads cold {cold.checks} times in a row without water')
                elif not pumping and not soak.done:          # hot again without water: it still burns
                    if a.water_empty():
                        break
                    a.backend.loginfo(f'[{self.name}] fire {fire_id} shows hot again with the pump off: '
                                      'watering it again')
                    a.start_pump()
                    pumping, flow = True, WaterFlow(a.backend.now())
                if detected is not None and cold.seen_hot and frozen == bool(detected):
                    frozen = not detected                # the detector lost it: nothing corrects the aim
                    self._freeze_aim(frozen)
        finally:
            a.stop_pump()
        yaw = float(pose[3])
        if cold.out:
            return True, 'extinguished', yaw
        if not cold.seen_hot:                           # the tank ran dry during a top-up
            raise TaskError(f'fire {fire_id} {NOT_SEEN_HOT}: the tank ran dry topping it up, left active')
        if dry_early is not None:
            why = (f'the tank ran dry {100 * dry_early:.0f} % into the soak (under ~dry_soak_min_share '
                   f'{100 * a.p.dry_soak_min_share:.0f} %): left for a top-up')
            a.backend.loginfo(f'[{self.name}] fire {fire_id}: {why}')
            return False, why, yaw
        out, why = dry_tank_verdict(cold)
        a.backend.loginfo(f'[{self.name}] fire {fire_id}: tank dry, {why}')
        return out, 'extinguished' if out else why, yaw

    def _say_why_not_counted(self, fire_id: int, pose, here, flowing: bool) -> None:
        """Log (throttled) why a cold answer does not count: no water flowing, off the watering pose (how far,
        how much turned), or the jet's height not on the hot spot yet."""
        why = [] if flowing else ['no water flowing (the tank level still)']
        off, turned = math.dist(pose[:3], here[:3]), abs(wrap_angle(here[3] - pose[3]))
        if not self._at(pose, here):
            tolerance = math.degrees(self.agent.p.yaw_tolerance)
            why.append(f'{off:.2f} m (by its fix) and {math.degrees(turned):.1f} deg off the watering pose (at '
                       f'most {WATERING_POSE_TOLERANCE} m for a UAV, {tolerance:.1f} deg)')
        if not self.on_jet:
            why.append("the jet's height not on the hot spot yet")
        self.agent.backend.loginfo_throttle(2.0, f'[{self.name}] fire {fire_id} reads cold, not counted: '
                                                 + '; '.join(why))

    def _hot(self, detected: Optional[bool], fire_id: int) -> Optional[bool]:
        """Hot, cold or no evidence (None), for the soak and the cold check: hot while the detector sees the fire
        (its frame is then locked), else the raw thermal image's contrast of the locked fire to its wall
        (FireContrast.answer). Why not the detector's "no fire": it drops a fire whose heat fell under its
        contrast test (30 degC over the frame's median) well before it is out.

        A fire the detector does not report (a top-up of a nearly full fire) is seen hot when the raw frame
        has a warm area standing thermal_contrast.LOCK_MIN_RISE x ~out_contrast over its wall (plane-fitted,
        so a sun-heated wall's slope is none): that area is locked and watered until it reads at the wall's
        level. Why (realistic benchmark on ed77bf3, seeds 101, 102, 108): fires left at 95-97 % by a tank that
        ran dry stood ~10 degC over their wall, under the detector's test, and every top-up then aborted as
        "not seen hot" until the end of the trial."""
        c = self.contrast
        if detected:
            c.lock_on_latest()
            c.answer()                                   # the frames so far are the hot fire's
            return True
        if not c.locked and c.was_locked:
            c.lock_on_latest(steady=True, relock=True)   # the fire unlocked by a turn of the aim, however faint
        elif not c.locked and self._raw_seen_hot(f'fire {fire_id} not reported by the detector',
                                                 "watered until it reads at its wall's level"):
            return True
        hot = c.answer()
        if hot is None and c.locked and not c.fresh():
            self.agent.backend.logerr_throttle(5.0, f'[{self.name}] fire {fire_id}: no raw thermal frame '
                                                    f'({RAW_THERMAL_TOPIC}) for {c.now() - c.frame_time:.1f} s: '
                                                    'not judged cold')
        elif hot is False and c.last == c.last:
            self.agent.backend.loginfo_throttle(2.0, f'[{self.name}] fire {fire_id} at its wall\'s level in the '
                                                     f'raw thermal image: {c.last:.1f} degC over it (locked at '
                                                     f'{c.locked_contrast:.1f}, cold at <= {c.out_contrast:.1f})')
        elif hot:
            self.agent.backend.loginfo_throttle(2.0, f'[{self.name}] fire {fire_id} unseen by the detector, still '
                                                     f'{c.last:.1f} degC over its wall in the raw thermal image')
        if c.bad:
            self.agent.backend.logerr_throttle(5.0, f'[{self.name}] {c.bad} raw thermal frames ignored (not 1024 '
                                                    'finite deg C)')
        return hot

    def _keep_aim(self, yaw: float) -> float:
        """While pumping: the watering heading, turned onto the hot spot of the latest thermal detection (at
        most AIM_MAX_AGE s old) when it is ~aim_bearing_tolerance or more off it, and (UAV) the height
        steered onto it (_height_target). Why: a UAV's set-point moves with its GNSS error's drift, and the
        bearing and height of the fire with it."""
        a = self.agent
        seen = self._sighted(a.backend.now() - AIM_MAX_AGE, 0.0)
        new_yaw = None if seen is None else self._correct_aim(seen, yaw)
        if new_yaw is None:
            return yaw
        self._turn_in_place(new_yaw)
        return new_yaw

    def _steer_for(self, seconds: float, yaw: float, frozen: bool) -> float:
        """While pumping, for `seconds`: every STEER_PERIOD s the aim (heading yaw, and a UAV's height) steered
        onto the fire, by the detector's sighting (`_keep_aim`) or, frozen, the raw thermal image
        (`_steer_on_raw_image`, the height held by the altimeter); the heading it ends at. Why every STEER_PERIOD
        and not once a WATER_PERIOD: gusts push a UAV +-0.2-0.4 m sideways within a second or two, and the jet
        with it, 1:1 (ual_sim's realistic profile, closed loop test_indoor_closed_loop.py: the jet's end
        0.1-0.3 m beside the hole for much of a tank when the aim was corrected twice a second)."""
        now = self.agent.backend.now
        end = now() + seconds
        while True:
            self.sleep(max(0.0, min(STEER_PERIOD, end - now())))
            if frozen:
                self._hold_frozen_height(yaw)
                yaw = self._steer_on_raw_image(yaw)
            else:
                yaw = self._keep_aim(yaw)
            if now() >= end - 1e-6:
                return yaw

    def _freeze_aim(self, frozen: bool) -> None:
        """Freeze (or free) the aim that put water in: the heading is held as it is (no sighting turns it),
        and a UAV's height is held on its true height, the held set-point less the vertical GNSS error its
        altimeter estimates (the source least affected by GNSS drift), re-sent as that error wanders; without
        an altimeter estimate the commanded set-point is held as it is (never re-derived from GNSS)."""
        a = self.agent
        self.frozen_true_z = None
        if not frozen or a.ROBOT_TYPE != 'uav':
            return
        self.aim_z = self._held_z(a.position())
        e = a.clearance.vertical_error()
        if e is not None:
            self.frozen_true_z = self.aim_z - e
        a.backend.loginfo(f'[{self.name}] the detector no longer sees the fire: aim frozen at {self.aim_z:.2f} m '
                          '(GNSS), ' + ('held by the altimeter' if e is not None else 'no altimeter estimate: set-point held'))

    def _steer_on_raw_image(self, yaw: float) -> float:
        """While the aim is frozen (the detector no longer reports the fire): the heading turned onto the warm
        area of the raw thermal image when it is ~aim_bearing_tolerance or more off it (~forward_camera_fov
        turns its pixel into a bearing), from a frame taken RAW_TURN_SETTLE s or more after the last such turn.
        The locked pixels no longer hold the fire then: they are dropped and the fire is locked again on the
        next steady frames (until then no answer counts, hot or cold). Why: a UAV holds its GNSS set-point, so
        the drift of its GNSS error moves it sideways off where it watered from and the frozen jet off the fire
        (tenths of a metre in tens of seconds), while the raw image still sees the fire 15-25 degC over its
        wall; the height stays held by the altimeter (`_hold_frozen_height`). A frame whose fire is cut by its
        edge around no hole (thermal_contrast.warm_spot: not whole) turns nothing: from the watering distance
        its centroid may lie on the wrong side of the image centre (ual_sim's realistic world, 1.0 m from the
        wall: a fire 6 deg left read 3 deg right; realistic seed 103: a UAV its GNSS drift had taken within 1.0 m
        of the wall turned -13 deg twice in a row, then its tank ran dry)."""
        a = self.agent
        spot = self.contrast.warm_spot()
        if spot is None or not spot.whole or spot.time < self.raw_turn_time + RAW_TURN_SETTLE:
            return yaw
        bearing = pixel_bearing(spot.column, a.p.forward_camera_fov)
        climb = self._raw_climb(spot)
        turn = abs(bearing) >= a.p.aim_bearing_tolerance
        if not turn and climb is None:
            return yaw
        new_yaw = float(a.pose_at(spot.time)[3]) + bearing if turn else yaw
        if climb is not None:
            self.aim_z += climb
            if self.frozen_true_z is not None:
                self.frozen_true_z += climb
        self._turn_in_place(new_yaw)
        self.raw_turn_time = a.backend.now()
        self.contrast.unlock()
        turned = math.degrees(wrap_angle(new_yaw - yaw))
        a.backend.loginfo_throttle(2.0, f'[{self.name}] frozen aim turned {turned:+.1f} deg, '
                                        f'{climb or 0.0:+.2f} m up onto the warm area of the raw thermal image')
        return new_yaw

    def _raw_climb(self, spot) -> Optional[float]:
        """m a UAV's frozen aim climbs to put the raw image's warm spot (column, row, time, whole) where the jet
        lands (~jet_rise above the optical axis at ~indoor_fire_distance), at most ~aim_height_step and within
        ~aim_height_range of the watering height; None when it is there (~aim_height_tolerance) or cannot climb.
        Why: the aim frozen on the altimeter holds the height the detector last saw the fire at, and the
        spot's row was not followed while the fire faded (ual_sim's realistic profile, closed loop
        test_indoor_closed_loop.py: the jet's end 0.1-0.2 m off the hole once the detector lost the fire)."""
        a = self.agent
        if a.ROBOT_TYPE != 'uav' or self.watering_z is None or self.aim_z is None:
            return None
        error = a.p.indoor_fire_distance * math.tan(pixel_bearing(spot.row, a.p.forward_camera_fov)) - a.p.jet_rise
        if abs(error) < a.p.aim_height_tolerance:
            return None
        step = max(-a.p.aim_height_step, min(a.p.aim_height_step, error))
        reach = a.p.aim_height_range
        z = max(self.watering_z - reach, min(self.watering_z + reach, self.aim_z + step))
        return None if abs(z - self.aim_z) < 1e-3 else z - self.aim_z

    def _hold_frozen_height(self, yaw: float) -> None:
        """The frozen aim's height set-point follows the altimeter's estimate of the vertical GNSS error, so
        that the UAV's true height (where the jet lands) stays put; unchanged without an estimate."""
        if self.frozen_true_z is None:
            return
        e = self.agent.clearance.vertical_error()
        if e is None:
            return
        z = self.frozen_true_z + e
        if abs(z - self.aim_z) >= FROZEN_HEIGHT_STEP:
            self.aim_z = z
            self._turn_in_place(yaw)

    def _heading_at(self, pose, here) -> bool:
        return abs(wrap_angle(here[3] - pose[3])) <= self.agent.p.yaw_tolerance

    def _at(self, pose, here) -> bool:
        """Still at the watering pose: looking where the fire was seen hot. A UAV: position (its autopilot holds
        it on the GNSS fix, so the fix says where it is against the pose: a gust pushes it off) and heading.
        A UGV: heading only. Why: at rest its controller holds no position, so it stands still while its fix
        wanders (a GNSS bias of ~0.5 m correlated over ~30 s moves the fix ~0.5 m in 10 s, z too), and it
        translates only when told (the wall back-off moves the pose with it). Judged by the fix, a UGV that
        put its fire out on its first tank was "off its watering pose" for every cold answer in 6 of 8
        realistic benchmark runs (6b5ecb7: 'the tank ran dry before 6 cold answers (0 so far)')."""
        if self.agent.ROBOT_TYPE == 'uav' and math.dist(pose[:3], here[:3]) > WATERING_POSE_TOLERANCE:
            return False
        return self._heading_at(pose, here)

    def _seen_hot(self, cold: ColdConfirmation, seconds: float, raw_too: bool = False) -> bool:
        """Poll CheckFire for up to seconds (its frame filter needs > 1 s of hot frames) until hot. raw_too
        (just turned onto a fire the detector reported): hot also when, the detector silent, the raw thermal
        image shows a steady warm area thermal_contrast.LOCK_MIN_RISE x ~out_contrast over its wall (locked).
        Why (explore + GNSS-denied seed 109 on e45b72d): a top-up robot saw in1_w (69 % out) with the detector
        29 deg aside, turned onto it, and from 1.5 m its ring of flames filled the view: the frame's median rose
        with it, the detector's contrast test (30 degC over the median) failed, and the goal aborted 'hot before
        aiming, cold after' three times without water; the fire was doubted and left burning."""
        end = self.agent.backend.now() + seconds
        while True:
            cold.update(self.agent.fire_detected())
            if cold.seen_hot:
                self.contrast.lock_on_latest()           # the fire as seen hot, for the raw cold check
                return True
            if raw_too and self._raw_seen_hot('aimed at the fire: the detector no longer reports it'):
                cold.update(True)
                return True
            if self.agent.backend.now() >= end:
                return False
            self._wait_off_walls(0.25, self.agent.position()[3])

    def _raw_seen_hot(self, why: str, then: str = '') -> bool:
        """The raw thermal image's steady warm area, thermal_contrast.LOCK_MIN_RISE x ~out_contrast over its wall,
        locked as the fire (True, logged with why and what follows), or none (False). The one rule by which a
        fire the detector does not report is seen hot: a top-up's faint fire (`_hot`), a fire aimed at from so
        near that it fills the view (`_seen_hot`)."""
        if not self.contrast.lock_on_latest(steady=True):
            return False
        self.agent.backend.loginfo(f'[{self.name}] {why}, but {self.contrast.locked_contrast:.1f} degC over its wall '
                                   f'in the raw thermal image: seen hot' + (f', {then}' if then else ''))
        return True

    def _well_localised(self, fire_id: int) -> bool:
        """A confirmed track known to ~top_up_max_std: a real fire, not a stray estimate.

        The threshold must stay above the estimator's floor on a track's std (its ~pose_std, the robots'
        GNSS error): below it no track ever qualifies and every fire a dry tank left is abandoned."""
        obj = self.agent.fire(fire_id)
        cov = obj.pose.covariance
        std = math.sqrt(max(cov[0], cov[7], 0.0))
        return (obj.status in (C.STATUS_ACTIVE, C.STATUS_LOST) and obj.num_updates >= TOP_UP_MIN_UPDATES
                and math.isfinite(std) and std <= self.agent.p.top_up_max_std)
