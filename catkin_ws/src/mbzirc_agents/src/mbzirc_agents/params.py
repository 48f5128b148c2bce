"""AgentParams: every ~param of an agent node, once: its name, type, default and meaning.

Why a dataclass: the tasks read `agent.p.<name>` (typed, spelled once) instead of `float(a.p['<name>'])`
in many places; a misspelt or malformed param is reported at start with a message that names it (the
node logs it and keeps the default), not found in the middle of a trial. The UGV changes some defaults
(`ugv_agent.UGV_DEFAULTS`).
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, fields
from typing import Any, Dict, List, Mapping, Sequence, Tuple

from . import constants as C

# Private params of the agent nodes that other code reads: the backend's service time bound and smach_ros's
# introspection server switches. They are not agent params, and not unknown either.
OTHER_NODE_PARAMS = ('service_timeout', 'smach_allow_init', 'smach_allow_debug', 'smach_exclude_keys')


class ParamError(ValueError):
    """One or more ~params are unknown or malformed; the message names each."""


def _param(default: Any, meaning: str, lengths: Sequence[int] = (), choices: Sequence[str] = ()) -> Any:
    """A field with its one-line meaning; `lengths`: allowed list lengths; `choices`: allowed strings."""
    return field(default_factory=lambda: copy.deepcopy(default),
                 metadata={'meaning': meaning, 'lengths': tuple(lengths), 'choices': tuple(choices)})


def _points(seq: Sequence[Sequence[float]]) -> List[List[float]]:
    return [[float(v) for v in p] for p in seq]


@dataclass
class AgentParams:
    """The agent's ~params (README "Params"); build with `from_dict`, which checks every value."""
    uav_id: str = _param('1', "the agent's id (also the UGV's)")
    payload: str = _param('water', 'what the robot carries', choices=('water', 'blanket'))
    central_unit_timeout: float = _param(C.CENTRAL_UNIT_TIMEOUT, 's (wall) of heartbeat silence before the '
                                         'running task is stopped and goals are rejected')
    return_home_timeout: float = _param(C.RETURN_HOME_TIMEOUT, 's (wall) of further silence before a flying '
                                        'UAV goes home by itself')
    arena: List[float] = _param(list(C.ARENA_BOX), 'x_min, y_min, z_min, x_max, y_max, z_max of the arena: '
                                'goals outside are refused', lengths=(6,))
    use_regions: bool = _param(True, 'reserve every motion with /ask_for_region')
    fault_injection: bool = _param(False, 'test only: serve inject_fault (std_srvs/Trigger), after which the '
                                          "state machine's next step raises (the fault suite)")
    region_margin: float = _param(C.REGION_MARGIN, 'm added around the box reserved for each flight leg')
    region_timeout: float = _param(C.REGION_WAIT_TIMEOUT, 's a motion waits for its region')
    hold_half_size: float = _param(C.HOLD_HALF_SIZE, 'm, half side of the box a hovering UAV holds')
    pose_error_margin: float = _param(C.POSE_ERROR_MARGIN, 'm added in x and y on each side of every box reserved '
                                      'in the air, for the error of the reported pose (pose_error_boxes.py)')
    pose_error_margin_z: float = _param(C.POSE_ERROR_MARGIN_Z, 'm added in z on each side of every reserved box, '
                                        'for the error of the reported height')
    step_aside_max: float = _param(4.0, 'm, longest step a hovering UAV takes out of another UAV\'s box when '
                                   'the region manager breaks a deadlock (region_yield.py)')
    step_aside_min_z: float = _param(2.0, 'm, lowest height such a step goes down to')
    position_tolerance: float = _param(C.POSITION_TOLERANCE, 'm from a waypoint that counts as there')
    yaw_tolerance: float = _param(C.YAW_TOLERANCE, 'rad from a waypoint yaw that counts as there')
    max_speed: float = _param(1.6, 'm/s; motion time-outs assume half of it')
    max_vertical_speed: float = _param(1.2, 'm/s, vertical (read by no task yet: the UAL limits the climb rate)')
    tank_capacity: float = _param(2.0, 'L, a full tank (refilled means 95 % of it)')
    water_empty: float = _param(0.05, 'L under which the tank is empty')
    cruise_altitude: float = _param(4.0, 'm go_home_and_refill climbs to at least, before flying home: its boxes '
                                    '(grown by the pose error) then clear the parked UAVs\' (pose_error_boxes.py)')
    parked_half_size: float = _param(0.75, 'm: a landed UAV keeps the box x, y +- this, z 0..parked_height')
    parked_height: float = _param(2.0, 'm, top of the parked box above the ground')
    refill_timeout: float = _param(60.0, 's waiting at home for a full tank / a new blanket')
    reland_after: float = _param(20.0, 's landed at home without the reset before landing on the pad again '
                                       '(the GNSS landing may miss it)')
    reland_attempts: int = _param(2, 'landings again on the pad before the last ~refill_timeout wait (0: none)')
    reland_height: float = _param(4.0, 'm of the take-off before landing on the pad again (its hold box clears '
                                  'the neighbours\' parked boxes, as ~cruise_altitude)')
    home_landing_offset: float = _param(0.5, "m off its pad's centre a UAV aims its landing, away from the other "
                                        "UAVs' pads (tasks/uav_motion.landing_spot): about the GNSS error of one "
                                        'fix, well inside HOME_PAD_RADIUS (1.5 m); 0: the centre')
    pad_laser_fix: bool = _param(True, 'going home, a UAV corrects its GNSS error over the pad (and again low over '
                                 'it) by its laser on the buildings\' outer walls (pad_fix.py) before it lands; '
                                 'false: the landing is flown on GNSS')
    pad_approach_height: float = _param(1.0, 'm above the ground (true, by the altimeter) a UAV goes down to over '
                                        'its pad by a go-to before the laser fix and the UAL\'s landing')
    facade_holders: List[List[float]] = _param(_points(C.FACADE_HOLDERS), 'x, y, z of the facade fire holders '
                                               'search_facade visits when its goal has no path', lengths=(3,))
    facade_standoff: float = _param(C.FACADE_STANDOFF, 'm in front of a facade fire holder to check it')
    shoot_distance: float = _param(1.5, 'm from the hole while shooting water')
    min_wall_distance: float = _param(1.0, 'm: the centring loop never moves the UAV closer to a facade')
    check_fire_time: float = _param(4.0, 's of looking for a fire at a holder / viewpoint')
    confirm_time: float = _param(6.0, "s waiting for the estimator's track of a detected fire")
    centering_timeout: float = _param(30.0, 's to centre a hole / a ground fire before giving up')
    extinguish_timeout: float = _param(60.0, 's of extinguishing before giving up')
    stop_at_first_fire: bool = _param(True, 'a search returns at the first new fire')
    ground_search_area: List[float] = _param(list(C.GROUND_SEARCH_AREA), 'x_min, y_min, x_max, y_max of the '
                                             'default lawn-mower ground search', lengths=(4,))
    ground_search_height: float = _param(4.0, 'm above the ground of the ground search')
    ground_search_spacing: float = _param(3.0, 'm between the lawn-mower legs')
    ground_check_time: float = _param(1.5, 's of dwell at each ground-search waypoint (frame filter > 1 s)')
    blanket_release_height: float = _param(1.5, 'm above the fire where the blanket is released')
    downward_camera_fov: float = _param(33.0, 'degrees, field of view of the downward thermal camera (the '
                                        "TeraRanger Evo Thermal 33's datasheet): sets the ground it covers")
    detector_wait: float = _param(30.0, 's a look goes on waiting for a thermal detector that has not answered '
                                  'once yet (it starts after the agent on a loaded machine) before the search fails')
    forward_camera_fov: float = _param(33.0, 'degrees, field of view of the forward thermal camera (the '
                                       "TeraRanger Evo Thermal 33's datasheet): turns a warm area's pixel into "
                                       'a bearing when the detector no longer reports the fire')
    ground_fire_search_radius: float = _param(2.0, "m around a ground fire's estimate searched with the "
                                              'downward camera when it does not see the fire from over it '
                                              '(the GNSS errors of the UAV and of whoever placed the fire)')
    ground_fire_search_time: float = _param(60.0, 's at most of that search before giving up (blanket kept)')
    entry_depth: float = _param(3.5, 'm flown in through a window, from the entry pose (the central unit\'s '
                                'is 2 m outside it)')
    laser_openings: bool = _param(True, 'windows and doors are passed guided by the laser (`scan`): centred '
                                  'on the opening it sees, then through; false: a straight leg in the arena frame')
    opening_width: float = _param(0.0, 'm, width of the window / door the laser looks for; 0: the arena '
                                  "model's width of the nearest one")
    opening_width_tolerance: float = _param(0.4, 'm: an opening seen this much narrower or wider is not it')
    opening_standoff: float = _param(1.0, 'm from the wall kept at least while centring on an opening')
    opening_tolerance: float = _param(0.12, "m off the opening's middle that counts as centred")
    opening_speed: float = _param(0.4, 'm/s towards an opening (centred on it) and backing out of it')
    opening_pass_speed: float = _param(0.8, "m/s across the opening's wall (the robot's frame within reach "
                                       'of its edges): brisk, so that gusts have little time to push it aside')
    opening_lateral_gain: float = _param(2.5, "1/s: sideways velocity per m off the opening's middle (centring "
                                         'and going through)')
    opening_lateral_vmax: float = _param(1.0, "m/s: at most sideways onto the opening's middle (and backing off)")
    frame_radius: float = _param(0.4, "m: the robot's own half size across (UAV frame with its propellers; "
                                 "UGV chassis): what must clear an opening's edges")
    opening_pass_margin: float = _param(0.25, "m: the robot's frame goes into the opening's wall only this much "
                                        'clear of its edges (what a gust may push it while it crosses)')
    opening_timeout: float = _param(20.0, 's to find and centre on an opening, and without progress through it, '
                                          'before giving up (holding; backing out when in it)')
    opening_jump_max: float = _param(0.5, "m the opening's middle may move between two scans (beyond the "
                                     "robot's own motion) before the passage is aborted")
    opening_keep_off: float = _param(0.6, 'm: in an opening, no velocity towards a laser return nearer than '
                                     'this (from the laser, the robot centre)')
    indoor_fire_distance: float = _param(1.5, 'm from an indoor fire while shooting')
    leg_guard: bool = _param(True, 'indoor straight legs (move, indoor go_to) stop and fail when the laser (`scan`) '
                             'sees a return ahead on them (leg_guard.py)')
    leg_guard_half_width: float = _param(0.6, 'm either side of the leg where a laser return blocks it: the '
                                         "robot's half width plus a margin")
    leg_guard_stop_distance: float = _param(0.9, 'm ahead of the robot centre (the laser) within which a return '
                                            'in that corridor stops the leg: its radius plus a stopping gap')
    wall_clearance: bool = _param(True, 'indoors, the watering pose stops at ~indoor_fire_distance from the wall the '
                                  'laser sees ahead, and the robot holding there keeps ~min_wall_clearance from '
                                  'every wall (wall_clearance.py)')
    min_wall_clearance: float = _param(1.0, 'm from the robot centre (the laser) to the nearest wall return '
                                       'below which a robot holding indoors backs off: its radius plus a gap '
                                       'for gusts and GNSS drift')
    wall_clearance_margin: float = _param(0.2, 'm beyond ~min_wall_clearance a back-off goes to (hysteresis)')
    lost_back_out_after: float = _param(5.0, 's with no trusted pose indoors after which an idle robot backs out '
                                        'the way it came (way_back.py; <= 0: never)')
    aim_bearing_tolerance: float = _param(0.03, 'rad: an indoor fire this far off the heading in the thermal '
                                          'image is straight ahead (else the robot turns to it first)')
    aim_height_tolerance: float = _param(0.05, 'm: a UAV whose indoor fire is this near the height its jet lands '
                                         'at (by the thermal image) is level with it (else it climbs or sinks)')
    aim_height_step: float = _param(0.3, 'm at most of one height correction onto an indoor fire')
    aim_height_range: float = _param(1.0, 'm at most a UAV moves up or down from its watering height to aim')
    jet_rise: float = _param(0.0, 'm the jet lands above the thermal camera\'s optical axis at '
                             '~indoor_fire_distance (the robot\'s nozzle and camera mounting; 0: level)')
    top_up_time: float = _param(3.0, 's of water on a confirmed, well-localised indoor fire that reads cold')
    soak_fraction: float = _param(0.25, 'share of the water that made an indoor fire read cold pumped on, aim '
                                  'frozen, before its cold check (a fire no longer seen may still burn)')
    soak_min_time: float = _param(1.0, 's at least of that soak')
    dry_soak_min_share: float = _param(0.33, 'share of the soak\'s litres pumped before the tank ran dry for the '
                                       'fire to be confirmed out with the pump off; less: left for a top-up')
    out_contrast: float = _param(2.0, 'deg C: an indoor fire is cold when its locked hot area reads no more than '
                                 'this above its wall in the raw thermal image (the noise level of a mean over '
                                 'its pixels, thermal_contrast.py)')
    thermal_period: float = _param(0.2, 's at least between the raw thermal frames measured while watering')
    top_up_max_std: float = _param(1.0, 'm: a track is well localised for a top-up when its position std is '
                                        'at most this (above the estimator\'s ~pose_std floor, 0.7 m)')
    building_clearance: float = _param(1.5, 'm kept from the buildings by planned paths')
    min_clearance: float = _param(0.5, 'm: no go-to or velocity command takes a flying UAV (not taking off or '
                                  'landing) closer to the surface below, by its altimeter (`altimeter`)')
    clearance_fallback_margin: float = _param(1.0, 'm more clearance, on the GNSS height above the arena plan, '
                                              'while the altimeter gives no valid reading')
    altimeter_max_age: float = _param(1.5, 's (sim): an older altimeter reading is stale (the fallback applies)')
    clearance_guard: bool = _param(True, 'false: motion commands pass unbounded (as without an altimeter; '
                                         'for comparisons)')
    pose_jump_max: float = _param(3.0, 'm: a reported pose this far from the last one is a GNSS jump, doubted')
    pose_jump_hold: float = _param(2.0, 's the robot holds (zero velocity) while doubting a jump; a jumped '
                                   'pose still reported after that is accepted')
    use_localization: bool = _param(True, 'with no GNSS fix (ual/gnss_status) fly on localization/pose while '
                                    'localization/source says slam (pose_source.py); false: on the UAL pose always')
    localization_timeout: float = _param(1.0, 's (sim): an older localization/pose is not valid')
    localization_pair_gap: float = _param(0.2, 's: a localization/pose is paired with the UAL poses at most this '
                                          'far from its stamp (the offset between the frames)')
    pose_source_grace: float = _param(0.5, 's a pose source of none (no fix, no valid localization) must last '
                                      'before the robot holds and its task fails')
    anchor_wait: float = _param(30.0, 's (sim) a robot waits at a window or door for the indoor localization '
                                'to be anchored (its pose heard) before going in, when one runs; then the task fails')
    pose_offset_rate: float = _param(0.5, 'm/s: the UAL-to-arena offset applied follows the measured one at '
                                     'most this fast (no jump of the pose when the source switches)')
    home: List[float] = _param([], 'x, y, z of home; empty: the first pose received', lengths=(0, 3))
    door_outside: List[float] = _param(list(C.UGV_DOOR_OUTSIDE), 'UGV: x, y in front of the door',
                                       lengths=(2,))
    door_inside: List[float] = _param(list(C.UGV_DOOR_INSIDE), 'UGV: x, y just inside the door', lengths=(2,))
    indoor_search_path: List[List[float]] = _param(_points(C.UGV_INDOOR_PATH), 'UGV: x, y[, yaw] of the '
                                                   'indoor viewpoints', lengths=(2, 3))
    indoor_search: str = _param('explore', "search_indoor: 'explore' follows the goal's path, then explores the "
                                "floor on the laser's free space (tasks/explore.py; UGV: the door only, no "
                                "~indoor_search_path); 'plan' follows the goal's path (UGV: and ~indoor_search_path) "
                                "only (the first wave's plan, read from the simulator's interior: a test aid)",
                                choices=('explore', 'plan'))
    explore_budget: float = _param(300.0, 's at most of exploring a floor, after the path')
    explore_headings: int = _param(0, 'headings of a look around on the spot while exploring (thermal camera); 0: '
                                   'enough for ~forward_camera_fov to cover the whole turn')
    explore_look_time: float = _param(1.5, 's of thermal look at each heading (the frame filter needs > 1 s)')
    explore_clearance: float = _param(0.8, 'm from every laser return and the outline a viewpoint and its legs '
                                      'keep')
    explore_pass_clearance: float = _param(0.6, 'm from every laser return a leg keeps at least where it cannot keep '
                                           '~explore_clearance (a doorway: its passage is centred by the laser)')
    explore_view_clearance: float = _param(2.0, 'm from every laser return a viewpoint keeps when one can: a thermal '
                                           'camera (~forward_camera_fov) near a wall sees only a strip of it')
    explore_view_range: float = _param(3.5, 'm: free space farther than this from every look-around is a viewpoint '
                                       'to go to (the thermal camera sees fires nearer than the laser sees walls)')
    explore_resolution: float = _param(0.25, 'm, cell side of the exploration grid')
    explore_min_frontier: int = _param(3, 'cells of a frontier at least (fewer: a missed beam, not unseen space)')
    explore_in_sight: bool = _param(True, 'exploration viewpoints only in straight sight of the first one (a '
                                    'UAV leaves through the window it came in)')

    @classmethod
    def names(cls) -> List[str]:
        return [f.name for f in fields(cls)]

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> 'AgentParams':
        """The params with `values` over the defaults; one ParamError naming each unknown or malformed one."""
        good, problems = check_values(values)
        if problems:
            raise ParamError('; '.join(problems))
        return cls(**good)


def check_values(values: Mapping[str, Any]) -> Tuple[Dict[str, Any], List[str]]:
    """(the well-formed values, each as its param's type; a message for each unknown or malformed one)."""
    known = {f.name: f for f in fields(AgentParams)}
    good: Dict[str, Any] = {}
    problems = []
    for name, value in values.items():
        if name not in known:
            problems.append(f'unknown param ~{name}')
            continue
        try:
            good[name] = _check(known[name], value)
        except ValueError as e:
            problems.append(f'~{name}: {e} (default {getattr(AgentParams(), name)!r})')
    return good, problems


def _number(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f'expected a finite number, got {value!r}')
    return float(value)


def _numbers(value: Any, lengths: Sequence[int]) -> List[float]:
    if not isinstance(value, (list, tuple)):
        raise ValueError(f'expected a list of numbers, got {value!r}')
    if lengths and len(value) not in lengths:
        raise ValueError(f'expected {" or ".join(map(str, lengths))} numbers, got {len(value)}')
    return [_number(v) for v in value]


def _check(f: Any, value: Any) -> Any:
    """value as the field's type; ValueError saying what is wrong."""
    kind, lengths, choices = f.type, f.metadata['lengths'], f.metadata['choices']
    if kind == 'float':
        return _number(value)
    if kind == 'int':
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise ValueError(f'expected a whole number >= 0, got {value!r}')
        return value
    if kind == 'bool':
        if not isinstance(value, bool):
            raise ValueError(f'expected true or false, got {value!r}')
        return value
    if kind == 'str':
        if isinstance(value, bool) or not isinstance(value, (str, int)):
            raise ValueError(f'expected a string, got {value!r}')
        if choices and str(value) not in choices:
            raise ValueError(f'expected one of {list(choices)}, got {value!r}')
        return str(value)
    if kind == 'List[float]':
        return _numbers(value, lengths)
    if kind == 'List[List[float]]':
        if not isinstance(value, (list, tuple)):
            raise ValueError(f'expected a list of points, got {value!r}')
        return [_numbers(v, lengths) for v in value]
    raise TypeError(f'no check for a param of type {kind}')

