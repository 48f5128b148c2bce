"""RobotAgent: what the UAV and UGV agents share on top of the framework.

It senses (UAL pose and state, water level, blanket, `/estimated_objects`, the central unit's heartbeat),
publishes `data_feed` at 10 Hz, serves `get_cost_to_go_to`, runs the heartbeat watchdog, and gives the
tasks their motion and payload primitives (fly/drive to a pose with monitoring, reserve regions, pump).
Agents never read `/sim/*`: everything comes from the robot's own interfaces.
"""
from __future__ import annotations

import math
import threading
from collections import deque
from typing import Any, Dict, Optional, Sequence

import numpy as np
from geometry_msgs.msg import PointStamped, PoseStamped, TwistStamped
from mbzirc_comm_objs.msg import AgentDataFeed, ObjectList
from mbzirc_comm_objs.srv import (AskForRegion, AskForRegionRequest, AskForRegionResponse, CheckFire, FreeRegions,
                                  FreeRegionsRequest, GetCostToGoTo, GetCostToGoToResponse, SetObjectStatus,
                                  SetObjectStatusRequest)
from sensor_msgs.msg import LaserScan, NavSatStatus
from std_msgs.msg import Bool, Float32, Header, String
from mbzirc_arena.boxes import Box, box_text, boxes_overlap, check_point, make_box
from mbzirc_arena.c3 import ARENA
from mbzirc_arena.laser import scan_points
from mbzirc_ros_utils.liveness import HeartbeatFilter
from mbzirc_arena.yaw import quaternion_from_yaw, wrap_angle, yaw_from_quaternion
from std_srvs.srv import Trigger, TriggerResponse
from uav_abstraction_layer.msg import State
from uav_abstraction_layer.srv import GoToWaypoint, GoToWaypointRequest

from . import constants as C
from . import heartbeat as hb
from .agent import Agent
from .agent_task import AgentTask, MoveTimedOut, TaskError, TaskPreempted
from .leg_guard import is_blind, malformed
from .params import AgentParams
from .pose_source import NONE, PoseSource
from .way_back import WayBack
from .pose_error_boxes import grown, pose_error_pad
from .region_yield import STEP_LABEL, step_aside_moves
from .wall_clearance import away_velocity, wall_ahead


# m: a held go-to set-point is sent to the UAL again once the UAL-to-arena offset moved this far since it was
# sent (the UAL's dead reckoning drifts a few cm/s indoors; pose_source.py)
FRAME_RESEND_DISTANCE = 0.1


def feed_content(msg: AgentDataFeed) -> tuple:
    """What a data_feed says, to the centimetre and the hundredth of a litre: two feeds with the same
    content tell nothing new (the stamp and the pose message's stamp left out)."""
    p, q = msg.pose.pose.position, msg.pose.pose.orientation
    return (round(p.x, 2), round(p.y, 2), round(p.z, 2), round(q.z, 3), round(q.w, 3), msg.ual_state,
            msg.active_task, msg.active_sub_state, round(msg.water_level, 2), msg.has_blanket, msg.payload)

VELOCITY_MAX_AGE = 0.5    # s: an older ual/velocity is no velocity
POSE_TOPIC = 'agent/pose'  # the agent's pose, published at every UAL pose (README, "Pose source")


class RobotAgent(Agent):
    """Base of UavAgent and UgvAgent. `params`: the node's ~params that are set (name -> value, see
    params.AgentParams; ParamError when one is unknown or malformed)."""
    ROBOT_TYPE = 'uav'

    def __init__(self, agent_id: str, backend: Any, params: Dict[str, Any], namespace: str = '') -> None:
        super().__init__(agent_id, backend, namespace)
        self.p = AgentParams.from_dict(params)
        self.arena = list(self.p.arena)
        self.state_lock = threading.Lock()
        self.pose: Optional[np.ndarray] = None          # x, y, z, yaw in the arena frame (pose_source.py)
        self.pose_msg: Optional[PoseStamped] = None
        # the UAL's pose or the indoor localization's, and the offset between the UAL's frame and the arena
        self.pose_source = PoseSource(self.p)
        self._ual_xyz: Optional[np.ndarray] = None      # the last accepted UAL position (its own frame)
        # the go-to set-point last sent (arena x, y, z, yaw) and the offset it was sent with; None while the
        # UAL follows velocities or its own take-off / landing
        self._set_point_lock = threading.RLock()
        self._set_point: Optional[tuple] = None
        self._set_point_offset = np.zeros(2)
        # (stamp s, pose) of the last seconds: detections are placed with the pose at their image's time
        self.pose_history: deque = deque(maxlen=C.POSE_HISTORY_LEN)
        self.pose_doubt_since: Optional[float] = None    # a GNSS jump is doubted since then (backend time)
        self.pose_time = -math.inf                       # backend time of the last accepted pose
        self.pose_stamp = -math.inf                      # its header stamp (the UAL's time of the fix)
        self.ual_state = C.UAL_UNINITIALIZED
        self.water_level = float('nan')
        self.blanket_attached = False
        self.objects: Dict[int, Any] = {}
        self.home: Optional[np.ndarray] = np.array(self.p.home) if self.p.home else None
        self._started_at_pose = False          # _settle_start done (home, a previous run's regions)
        self.pumping = False
        self.watchdog = hb.HeartbeatWatchdog(self.p.central_unit_timeout,
                                             self.p.return_home_timeout)
        self._went_home = False
        self._home_request = None
        self.hb_filter = HeartbeatFilter()     # replayed heartbeats are not believed (mbzirc_ros_utils.liveness)
        # Why wall time: /clock comes from the simulator on the ground station; when the link is cut the
        # robot's ROS time stops too, so a ROS-time watchdog would never fire.
        self.wall_clock = backend.wall_time
        self._watchdog_stop = threading.Event()
        self._watchdog_thread: Optional[threading.Thread] = None
        self.parked = False                # a 'parked' region is held while landed
        self.held: Dict[str, Box] = {}     # our granted boxes by label (as we asked for them)
        self._waiting_for: Optional[str] = None   # the label reserve() is waiting for (refused so far)
        self._yield_order: Optional[tuple] = None # (winner, label, box) the region manager asked us to leave
        self._regions_lock = threading.Lock()
        self._last_park_try = -1e9
        self._scan: Optional[tuple] = None      # (LaserScan, receive time, pose then or None, blind): latest_scan
        self._backing_off_blind = False          # moving off a wall by the laser with no trusted pose
        self.way_back = WayBack(C.BUILDINGS)     # the way in, backed out along with no trusted pose
        self._velocity: Optional[tuple] = None   # (stamp, vx, vy) of the UAL's latest velocity
        self._velocity_arrival = -math.inf
        self._travelled = np.zeros(2)            # its integral (m)
        self._lost_since: Optional[float] = None
        # (no message reaches a callback before start(): AgentInterface.close)
        ifc = self.iface
        # its pose as its pose source has it (arena frame): what a detector places what it sees with when there
        # is no GNSS indoors (the UAL's own pose dead-reckons there, a metre or more off after a minute)
        self.pose_pub = ifc.add_publisher(POSE_TOPIC, PoseStamped)
        ifc.add_subscriber(None, 'ual/pose', PoseStamped, self._on_pose)
        ifc.add_subscriber(None, 'ual/state', State, self._on_state)
        ifc.add_subscriber(None, 'ual/velocity', TwistStamped, self._on_velocity)
        ifc.add_subscriber(None, 'ual/gnss_status', NavSatStatus, self._on_gnss_status)
        ifc.add_subscriber(None, 'localization/source', String, self._on_localization_source)
        ifc.add_subscriber(None, 'localization/pose', PoseStamped, self._on_localization_pose)
        ifc.add_subscriber(None, 'actuators_system/water_level', Float32, self._on_water)
        ifc.add_subscriber(None, 'actuators_system/blanket_attached', Bool, self._on_blanket)
        ifc.add_subscriber(None, '/estimated_objects', ObjectList, self._on_objects)
        ifc.add_subscriber(None, C.HEARTBEAT_TOPIC, Header, self._on_heartbeat)
        ifc.add_subscriber(None, 'scan', LaserScan, self._on_scan)
        self.feed_pub = ifc.add_publisher('data_feed', AgentDataFeed)
        self.vel_pub = ifc.add_publisher('ual/set_velocity', TwistStamped)
        self.go_to_srv = ifc.add_client('ual/go_to_waypoint', GoToWaypoint)
        self.ask_srv = ifc.add_client('/ask_for_region', AskForRegion)
        self.free_srv = ifc.add_client('/free_regions', FreeRegions)
        self.status_srv = ifc.add_client('/set_object_status', SetObjectStatus)
        self.check_fire_srv = ifc.add_client('thermal_detection/fire_detected', CheckFire)
        self.pump_start_srv = ifc.add_client('actuators_system/start_pump', Trigger)
        self.pump_stop_srv = ifc.add_client('actuators_system/stop_pump', Trigger)
        ifc.add_service_server(None, 'get_cost_to_go_to', GetCostToGoTo, default_callback=self._on_cost)
        ifc.add_service_server(None, 'yield_region', AskForRegion, default_callback=self._on_yield_region)
        if self.p.fault_injection:       # the fault suite's "exception in a task" (test only)
            ifc.add_service_server(None, 'inject_fault', Trigger, default_callback=self._on_inject_fault)
        self._last_feed: tuple = (None, -1e9)   # content and ROS time of the last data_feed sent
        self.timer = backend.timer(1.0 / C.DATA_FEED_RATE_HZ, self._on_timer)

    def start(self) -> None:
        """Start the agent. The regions a previous run of this agent (killed, respawned) left behind are
        settled at the first pose (`_settle_start`): dropped when the robot is on the ground, kept when it
        is in the air (its airspace is still its own: a respawned UAV freed every region it held, mid-air)."""
        super().start()
        self._watchdog_thread = self.backend.start_thread('heartbeat_watchdog', self._watchdog_loop)
        self.backend.start_thread('set_point_keeper', self._set_point_loop)

    def _settle_start(self, xyz: np.ndarray) -> None:
        """At the first pose: choose home and what to do with the regions of a previous run.

        Home is `~home` when given, else the arena's home pad of this robot (known before the trial,
        mbzirc_arena) when the robot starts on it (within C.HOME_PAD_RADIUS: the reported pose carries the
        GNSS error, the pad's place does not), else this first pose when the robot is on the ground
        elsewhere; a first pose in the air is a respawned agent, never home: then the arena's home."""
        airborne = xyz[2] > C.ON_GROUND_MAX_Z
        if self.home is None:
            known = next((h.position for h in ARENA.homes if str(h.robot_id) == str(self.agent_id)), None)
            on_pad = known is not None and math.hypot(xyz[0] - known[0], xyz[1] - known[1]) <= C.HOME_PAD_RADIUS
            if not airborne and on_pad:
                self.home = np.array(known, dtype=float)
            elif not airborne:
                self.home = xyz.copy()
            elif known is not None:
                self.home = np.array(known, dtype=float)
                self.backend.logwarn(f'first pose in the air (z {xyz[2]:.1f} m, respawned?): home is the '
                                     f'arena home {tuple(self.home)}, not here')
            else:
                self.backend.logerr(f'first pose in the air (z {xyz[2]:.1f} m) and no ~home nor arena home '
                                    f'for robot {self.agent_id}: no home until it lands')
        if not self.p.use_regions:
            return
        if airborne:
            self.backend.logwarn('started in the air (respawned?): keeping the regions a previous run reserved')
            return

        def free_previous() -> None:
            try:
                self.free_srv(FreeRegionsRequest(agent_id=self.agent_id, free_all=True))
            except Exception:
                pass        # no region manager yet: then it holds nothing of ours either
        self.backend.start_thread('free_previous_regions', free_previous)

    # ---- sensing callbacks (always on) ------------------------------------------------------------
    def _on_pose(self, msg: PoseStamped) -> None:
        p, q = msg.pose.position, msg.pose.orientation
        yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
        vals = (p.x, p.y, p.z)
        if yaw is None or not all(map(math.isfinite, vals)):
            self.backend.logerr_throttle(5.0, 'ual/pose: NaN or invalid orientation, ignored')
            return
        now = self.backend.now()
        stamp = msg.header.stamp.to_sec() or now
        xyz = np.array([p.x, p.y, p.z])
        # the pose source sees every UAL pose first: a step while the UAL leaves its dead reckoning is its
        # frame's (absorbed into the offset), not a GNSS glitch to doubt (realistic seed 111, rtf 4: a 7.4 m
        # step doubted, the pose source never saw it, and the agent's pose stayed 6 m off, gliding back,
        # its held set-points flying the UAV into the facade)
        with self.state_lock:
            self.pose_source.on_ual(stamp, p.x, p.y)
            frame_changed = self.pose_source.frame_jump is not None
        if frame_changed:
            self._accept_pose(xyz, stamp)
        elif self._doubt_jump(xyz, stamp):
            return
        with self.state_lock:
            src = self.pose_source
            switched = src.update(now)
            frame_jump = src.take_frame_jump()
            x, y = src.to_arena(p.x, p.y)
            self.pose = np.array([x, y, p.z, yaw])
            self.pose_msg = msg if (x, y) == (p.x, p.y) else self._pose_msg_at(msg, x, y, p.z)
            if self.pose_history and stamp < self.pose_history[-1][0]:
                self.pose_history.clear()           # time went back (bag loop, sim restart)
            self.pose_history.append((stamp, self.pose))
            first = not self._started_at_pose
            self._started_at_pose = True
            lost = src.source == NONE
            why = src.why
            if lost:
                self._lost_since = now if self._lost_since is None else self._lost_since
            else:
                self._lost_since = None
                self.way_back.record(self.pose[:3])
        self.pose_pub.publish(self._detectors_pose(self.pose_msg))
        if frame_jump:
            self.backend.logwarn(frame_jump)
        if switched:
            (self.backend.logwarn if lost else self.backend.loginfo)(switched)
        if lost:
            self._on_pose_lost(why, bool(switched))
        if first:
            self._settle_start(np.array([x, y, p.z]))

    def _detectors_pose(self, msg: PoseStamped) -> PoseStamped:
        """The pose the robot's detectors place what they see with (agent/pose): its pose source's, at the
        height the UAL reports (a UAV's: its true height where its altimeter tells it, UavAgent)."""
        return msg

    @staticmethod
    def _pose_msg_at(msg: PoseStamped, x: float, y: float, z: float) -> PoseStamped:
        """msg (stamp, frame, orientation) at position (x, y, z): the arena position of the pose source (the
        data_feed's pose), or a true height (the detectors')."""
        out = PoseStamped()
        out.header = msg.header
        out.pose.orientation = msg.pose.orientation
        out.pose.position.x, out.pose.position.y, out.pose.position.z = x, y, z
        return out

    def _on_scan(self, msg: LaserScan) -> None:
        if malformed(msg):                       # the tasks' own laser views report bad scans
            return
        with self.state_lock:
            pose = None if self.pose is None else self.pose.copy()
        self._scan = (msg, self.backend.now(), pose, is_blind(msg.ranges))

    def latest_scan(self) -> Optional[tuple]:
        """(LaserScan, receive time, the agent's pose then (None before the first), blind) of the latest
        well-formed scan, None before one. Parsed once here for every task's laser view (leg_guard.LegGuard):
        each had subscribed on its own and checked every scan again (7 views per UAV, 15 scans a sim-second)."""
        return self._scan

    def _on_gnss_status(self, msg: NavSatStatus) -> None:
        with self.state_lock:
            self.pose_source.on_gnss(int(msg.status) >= NavSatStatus.STATUS_FIX)

    def _on_localization_source(self, msg: String) -> None:
        with self.state_lock:
            self.pose_source.on_localization_source(str(msg.data))

    def _on_localization_pose(self, msg: PoseStamped) -> None:
        p = msg.pose.position
        if msg.header.frame_id.lstrip('/') not in ('', C.GLOBAL_FRAME):
            self.backend.logerr_throttle(5.0, f'localization/pose in frame {msg.header.frame_id!r}, expected '
                                              f'{C.GLOBAL_FRAME!r}: ignored')
            return
        with self.state_lock:
            problem = self.pose_source.on_localization_pose(msg.header.stamp.to_sec() or self.backend.now(),
                                                            p.x, p.y)
        if problem:
            self.backend.logerr_throttle(5.0, problem)

    def _on_pose_lost(self, why: str, just_now: bool) -> None:
        """Pose source none (no GNSS fix and no valid localization): a go-to being flown stops where the robot
        is (zero velocity: the UAL holds its own pose), every go-to becomes a hold and the next motion of the
        running task fails with why (raise_if_lost: the central unit gives the work to another robot or
        later); a warning every few seconds while it lasts. Velocity commands go on: they are the laser-guided
        moves (a window's crossing, keeping off a wall), which need no position in the arena, and a UAV
        stopped in a window frame is left there to the gusts and the UAL's drift (realistic seed 105: a UAV
        that lost its pose while crossing a window at 0.8 m/s, stopped in it, hit the frame)."""
        if just_now:
            with self._set_point_lock:
                flying_to = self._set_point is not None
            if flying_to:
                self._hold_still()
            self.backend.logwarn(f'no trusted pose ({why}): go-tos hold, {self.running_task() or "no task"} '
                                 'fails at its next one')
        else:
            self.backend.logerr_throttle(5.0, f'no trusted pose ({why}): holding')

    def _accept_pose(self, xyz: np.ndarray, stamp: float) -> None:
        """xyz is the UAL's position now: the jump doubt's reference, no doubt pending."""
        self.pose_doubt_since = None
        self.pose_time, self.pose_stamp, self._ual_xyz = self.backend.now(), stamp, xyz

    def _doubt_jump(self, xyz: np.ndarray, stamp: Optional[float] = None) -> bool:
        """True when this reported position jumped more than ~pose_jump_max from the last accepted one, beyond
        what the robot can fly (~max_speed) between the two poses' stamps (a GNSS re-fix or a glitch): the
        robot holds with zero velocity and the pose is ignored for ~pose_jump_hold s; a jump still reported
        after that is the new truth of the receiver, accepted. A pose after a silence of more than a second
        (a link cut) is no jump: the robot may have moved.

        Why the stamps: on a loaded machine the agent's clock (/clock) and its pose callbacks lag by
        different amounts, so two poses received 0.5 s apart by its clock were published 2-4 s apart; a
        UAV flying at its speed moved 6 m between them and was held as if its GNSS had jumped
        (ground_station live_page rostest during a benchmark).

        Why hold with a velocity command: a waypoint is flown in the (jumped) GNSS frame, a zero velocity
        keeps the robot where it physically is; tasks keep their last pose meanwhile (send_waypoint and
        send_velocity hold instead, see pose_in_doubt)."""
        now = self.backend.now()
        stamp = now if stamp is None else float(stamp)
        with self.state_lock:
            last = None if self._ual_xyz is None or now - self.pose_time > 1.0 else self._ual_xyz.copy()
            flown = self.p.max_speed * max(0.0, stamp - self.pose_stamp)
        if last is None or float(np.linalg.norm(xyz - last)) <= self.p.pose_jump_max + flown:
            if self.pose_doubt_since is not None:
                self.backend.logwarn(f'ual/pose: back within {self.p.pose_jump_max:.1f} m of the last pose, '
                                     'moving on')
            self._accept_pose(xyz, stamp)
            return False
        if self.pose_doubt_since is None:
            self.pose_doubt_since = now
        if now - self.pose_doubt_since >= self.p.pose_jump_hold:
            self.backend.logwarn(f'ual/pose: jumped {np.linalg.norm(xyz - last):.1f} m and stayed there for '
                                 f'{self.p.pose_jump_hold:.1f} s: accepted as the new position')
            self._accept_pose(xyz, stamp)
            return False
        self.backend.logerr_throttle(2.0, f'ual/pose jumped {np.linalg.norm(xyz - last):.1f} m '
                                          f'(> {self.p.pose_jump_max:.1f} m): doubted, holding')
        self._hold_still()
        return True

    def _on_velocity(self, msg: TwistStamped) -> None:
        """Integrates the UAL's horizontal velocity over its own stamps (self._travelled): no jump when the
        pose source or the GNSS fix changes (passage._Odometer). A gap over VELOCITY_MAX_AGE is not bridged."""
        v = msg.twist.linear
        if not (math.isfinite(v.x) and math.isfinite(v.y)):
            return
        stamp = msg.header.stamp.to_sec() or self.backend.now()
        with self.state_lock:
            last = self._velocity
            if last is not None and 0.0 < stamp - last[0] <= VELOCITY_MAX_AGE:
                dt = stamp - last[0]                       # trapezoid between the two samples
                self._travelled = self._travelled + 0.5 * dt * (np.array(last[1:]) + (v.x, v.y))
            self._velocity = (stamp, float(v.x), float(v.y))
            self._velocity_arrival = self.backend.now()

    def travelled(self) -> Optional[np.ndarray]:
        """The integral of the UAL's horizontal velocity (arena-aligned m; its origin is arbitrary: use
        differences), None while the velocity is older than VELOCITY_MAX_AGE."""
        with self.state_lock:
            if self._velocity is None or self.backend.now() - self._velocity_arrival > VELOCITY_MAX_AGE:
                return None
            return self._travelled.copy()

    def pose_in_doubt(self) -> bool:
        """True while a GNSS jump is being doubted, or while no pose is trusted (pose source none): motion
        commands become a hold."""
        return self.pose_doubt_since is not None or not self.pose_source.valid

    def _hold_still(self) -> None:
        with self._set_point_lock:
            self._set_point = None
        if self.is_moving_state():
            msg = TwistStamped()
            msg.header.stamp = self._stamp()
            msg.header.frame_id = C.GLOBAL_FRAME
            self.vel_pub.publish(msg)

    def _on_state(self, msg: State) -> None:
        self.ual_state = int(msg.state)

    def _on_water(self, msg: Float32) -> None:
        self.water_level = float(msg.data)

    def _on_blanket(self, msg: Bool) -> None:
        self.blanket_attached = bool(msg.data)

    def _on_objects(self, msg: ObjectList) -> None:
        with self.state_lock:
            self.objects = {int(o.id): o for o in msg.objects}

    def _on_inject_fault(self, _req: Any) -> Any:
        self.backend.logwarn('fault injection requested: the next step of the state machine raises')
        self.inject_fault()
        return TriggerResponse(success=True, message='the next step of the state machine raises')

    def set_mission(self, mission: str) -> None:
        """This mission's id (the master's /run_id): heartbeats of another mission are refused."""
        self.hb_filter.mission = mission

    def _on_heartbeat(self, msg: Header) -> None:
        if msg is not None:
            ok, why = self.hb_filter.accept(str(getattr(msg, 'frame_id', '')), int(getattr(msg, 'seq', 0)))
            if not ok:
                self.backend.logerr_throttle(10.0, f'central unit heartbeat refused: {why}')
                return
        self.watchdog.beat(self.wall_clock())

    # ---- data feed + heartbeat watchdog -----------------------------------------------------------
    def _on_timer(self, _event: Any = None) -> None:
        """data_feed at DATA_FEED_RATE_HZ while it changes, every DATA_FEED_IDLE_PERIOD while it does not
        (a landed or hovering idle robot), not at all while nobody subscribes. Why: four feeds at 10 Hz to
        the central unit, the recorder and the ground station, mostly of robots waiting at home."""
        silent = self.sm_silent_for()
        if silent > C.SM_STALL_S:
            # the data_feed is this agent's heartbeat to the central unit: it stops when the state machine
            # stopped working, so that the central unit sees the robot silent and gives its work to others
            self.backend.logerr_throttle(10.0, f'state machine silent for {silent:.0f} s (stuck): data_feed withheld')
            return
        count = getattr(self.feed_pub, 'get_num_connections', None)
        if count is not None and count() == 0:
            return
        msg = self.data_feed()
        key, now = feed_content(msg), self.backend.now()
        last_key, last_time = self._last_feed
        if key == last_key and last_time <= now < last_time + C.DATA_FEED_IDLE_PERIOD:
            return
        self._last_feed = (key, now)
        self.feed_pub.publish(msg)

    def _watchdog_loop(self) -> None:
        """The watchdog at DATA_FEED_RATE_HZ on the wall clock (a WallTimer: runs when /clock stops)."""
        period = 1.0 / C.DATA_FEED_RATE_HZ
        while not self.backend.wait_event(self._watchdog_stop, period) and not self.backend.is_shutdown():
            try:
                self._watch_heartbeat()
            except Exception as e:             # never let the watchdog thread die
                self.backend.logerr_throttle(5.0, f'heartbeat watchdog: {e}')

    def shutdown(self) -> None:
        """Stop the watchdog thread, then the agent (Ctrl+C)."""
        self._watchdog_stop.set()
        super().shutdown()

    def data_feed(self) -> AgentDataFeed:
        """The agent's state for the central unit (and its heartbeat)."""
        msg = AgentDataFeed()
        msg.header.stamp = self._stamp()
        msg.header.frame_id = C.GLOBAL_FRAME
        msg.agent_id = self.agent_id
        msg.robot_type = self.ROBOT_TYPE
        msg.payload = self.p.payload
        with self.state_lock:
            if self.pose_msg is not None:
                msg.pose = self.pose_msg
        msg.ual_state = self.ual_state
        msg.active_task = self.running_task()
        msg.active_sub_state = f'FAILED: {self.failed}' if self.failed else self.active_sub_state
        with self.state_lock:
            lost = None if self.pose_source.valid else self.pose_source.why
        if lost is not None and not msg.active_task:
            msg.active_sub_state = f'{C.NO_TRUSTED_POSE}: {lost}'
        msg.is_idle = not msg.active_task and not self.failed
        msg.battery = 1.0                    # no battery model in the simulation
        msg.water_level = self.water_level if math.isfinite(self.water_level) else 0.0
        msg.has_blanket = self.blanket_attached
        return msg

    def _stamp(self) -> Any:
        import rospy
        return rospy.Time.from_sec(self.backend.now())

    def _watch_heartbeat(self) -> None:
        state = self.watchdog.state(self.wall_clock())
        if state == hb.OK:
            if not self.accepting:
                self.backend.logwarn('central unit heartbeat back: accepting goals again')
                self.accepting, self.reject_reason = True, ''
                if self._home_request is not None and not self._home_request.done.is_set():
                    self.preempt_running('central unit heartbeat back')
                self._went_home, self._home_request = False, None
            return
        if self.accepting:
            self.backend.logwarn('central unit heartbeat lost: stopping the task safely')
            self.accepting, self.reject_reason = False, 'central unit heartbeat lost'
            self.preempt_running('central unit heartbeat lost')
        if state == hb.RETURN_HOME and not self._went_home and not self.running_task():
            self._went_home = True
            self._home_request = self.return_home()

    def return_home(self) -> Any:
        """Start going home after a long heartbeat loss (UAV: go home and land); None if nothing to do."""
        return None

    # ---- state accessors for tasks ------------------------------------------------------------------
    def position(self, wait: float = 10.0) -> np.ndarray:
        """Current x, y, z, yaw; waits up to `wait` s for the first pose (a goal may come before the
        UAL's first message), then TaskError."""
        end = self.backend.now() + wait
        while True:
            with self.state_lock:
                if self.pose is not None:
                    return self.pose.copy()
            if self.backend.now() >= end or self.backend.is_shutdown():
                raise TaskError('no pose received on ual/pose')
            self.backend.sleep(0.1)

    def pose_at(self, stamp: float) -> np.ndarray:
        """x, y, z, yaw at time `stamp` (s), interpolated in the pose history; the oldest / newest pose
        outside it. Why: a detection from an image taken 0.3 s ago, placed with the current pose of a
        UAV pushed by the wind, lands beside the object (a decoy 0.7 m from the hole became "the hole")."""
        with self.state_lock:
            hist = list(self.pose_history)
        if not hist:
            return self.position()
        if stamp <= hist[0][0]:
            return hist[0][1].copy()
        if stamp >= hist[-1][0]:
            return hist[-1][1].copy()
        i = next(k for k in range(len(hist) - 1, 0, -1) if hist[k - 1][0] <= stamp)
        (t0, p0), (t1, p1) = hist[i - 1], hist[i]
        w = (stamp - t0) / (t1 - t0) if t1 > t0 else 1.0
        out = p0 + w * (p1 - p0)
        out[3] = p0[3] + w * wrap_angle(p1[3] - p0[3])
        return out

    def fire(self, fire_id: int) -> Any:
        """The estimated object with this id (an mbzirc_comm_objs/Object); ValueError when unknown."""
        with self.state_lock:
            obj = self.objects.get(int(fire_id))
        if obj is None or obj.type != C.TYPE_FIRE:
            raise ValueError(f'unknown fire id {fire_id} (not in /estimated_objects)')
        return obj

    def fires(self, sub_types: Sequence[int] = (), statuses: Sequence[int] = (C.STATUS_ACTIVE,)) -> list:
        """Estimated fires of the given sub-types (all when empty) and statuses."""
        with self.state_lock:
            objs = list(self.objects.values())
        return [o for o in objs if o.type == C.TYPE_FIRE and (not sub_types or o.sub_type in sub_types)
                and o.status in statuses]

    def check_point(self, p: Sequence[float], what: str = 'waypoint') -> None:
        """ValueError when p is NaN or outside the arena."""
        err = check_point(p, self.arena, what)
        if err:
            raise ValueError(err)

    # ---- motion primitives ----------------------------------------------------------------------------
    def send_waypoint(self, x: float, y: float, z: float, yaw: float) -> None:
        """ual/go_to_waypoint to the arena (x, y, z, yaw), not blocking; TaskError when refused. The UAL flies
        in its own frame: the target is sent plus the pose source's offset, and again whenever that offset
        moves (`_set_point_loop`). While the pose is in doubt: a hold."""
        if self.pose_in_doubt():
            self._hold_still()
            return
        with self._set_point_lock:
            self._set_point = (float(x), float(y), float(z), float(yaw))
            self._send_set_point()

    def _send_set_point(self) -> None:
        """Send the set-point in the UAL's frame (under _set_point_lock: a re-send never overtakes a new one)."""
        x, y, z, yaw = self._set_point
        with self.state_lock:
            offset = self.pose_source.applied.copy()
            ux, uy = self.pose_source.to_ual(x, y)
        self._set_point_offset = offset
        req = GoToWaypointRequest()
        req.waypoint.header.frame_id = C.GLOBAL_FRAME
        req.waypoint.header.stamp = self._stamp()
        req.waypoint.pose.position.x, req.waypoint.pose.position.y, req.waypoint.pose.position.z = ux, uy, z
        q = quaternion_from_yaw(yaw)
        o = req.waypoint.pose.orientation
        o.x, o.y, o.z, o.w = q
        req.blocking = False
        try:
            self.go_to_srv(req)
        except Exception as e:
            raise TaskError(f'ual/go_to_waypoint failed: {e}')

    def keep_set_point(self) -> None:
        """Send the held set-point again when the UAL-to-arena offset moved FRAME_RESEND_DISTANCE since it was
        sent (the UAL's drift without GNSS, a source switch): the robot holds or flies to the arena point, not
        to where the UAL's frame has gone. Forgotten when the UAL no longer flies the agent's go-tos."""
        with self._set_point_lock:
            if self._set_point is None:
                return
            if not self.is_moving_state():
                self._set_point = None
                return
            if self.pose_in_doubt():
                return
            with self.state_lock:
                moved = float(np.linalg.norm(self.pose_source.applied - self._set_point_offset))
            if moved >= FRAME_RESEND_DISTANCE:
                self._send_set_point()

    def _set_point_loop(self) -> None:
        """keep_set_point at the control rate (its own thread), until shutdown; errors are logged."""
        while not self.backend.is_shutdown():
            try:
                self.keep_set_point()
            except Exception as e:  # noqa: BLE001 - tried again at the next step
                self.backend.logerr_throttle(5.0, f'set-point keeper: {e}')
            self.backend.sleep(1.0 / C.CONTROL_RATE_HZ)

    def move_to(self, task: AgentTask, target: Sequence[float], yaw: Optional[float], what: str,
                tolerance: Optional[float] = None, stop_when: Optional[Any] = None,
                horizontal: bool = False, timeout: Optional[float] = None) -> bool:
        """Send a waypoint and watch the pose at the control rate until there (MoveTimedOut when not there
        in `timeout` s: by default the time at half ~max_speed plus 20 s).

        On preemption the robot is stopped where it is (hold) before TaskPreempted propagates. When
        stop_when() turns true on the way, the robot holds there and False is returned (True: arrived).
        `horizontal`: arrived once within the tolerance in x, y (a correction whose height is another
        loop's business, e.g. the clearance guard low over a pad).
        """
        cur = self.position()
        yaw = cur[3] if yaw is None else yaw
        tol = self.p.position_tolerance if tolerance is None else tolerance
        dist = float(np.linalg.norm(np.asarray(target[:3]) - cur[:3]))
        if timeout is None:
            timeout = dist / max(0.2, 0.5 * self.p.max_speed) + 20.0
        self.send_waypoint(target[0], target[1], target[2], yaw)
        held = self.pose_in_doubt()            # the waypoint became a hold: sent again once the doubt ends
        end = self.backend.now() + timeout
        try:
            while True:
                task.check_preempt()
                # a doubted GNSS jump turned the go-to into a hold (zero velocity, set-point dropped): once
                # the pose is trusted again the waypoint is flown on (before, the robot hovered until the
                # leg's time-out: go_home after an operator's recall failed in the live_page rostest)
                if self.pose_in_doubt():
                    held = True
                elif held:
                    held = False
                    self.send_waypoint(target[0], target[1], target[2], yaw)
                p = self.position()
                dxy = math.hypot(target[0] - p[0], target[1] - p[1])
                dz = abs(self.set_point_z(target) - p[2]) if self.ROBOT_TYPE == 'uav' and not horizontal else 0.0
                if dxy <= tol and dz <= tol and abs(wrap_angle(yaw - p[3])) <= self.p.yaw_tolerance:
                    return True
                if stop_when is not None and stop_when():
                    self.hold()
                    return False
                if self.backend.now() > end:
                    raise MoveTimedOut(f'{what}: not there after {timeout:.0f} s ({dxy:.1f} m left)')
                self.raise_if_crashed(what)
                self.raise_if_lost(what)
                task.feedback('MOVING', f'{what}: {math.hypot(dxy, dz):.1f} m to go')
                self.backend.sleep(1.0 / C.CONTROL_RATE_HZ)
        except TaskPreempted:
            self.hold()
            raise

    def raise_if_crashed(self, what: str = '') -> None:
        """TaskError when the UAL says UNINITIALIZED: the robot crashed, no task may go on commanding it."""
        if self.ual_state == C.UAL_UNINITIALIZED:
            raise TaskError(f'{what + ": " if what else ""}UAL state is UNINITIALIZED (crashed?)')

    def wait_for_indoor_pose(self, task: AgentTask, what: str) -> None:
        """Before going in through `what` (a window, the door): while an indoor localization runs and its pose
        is not anchored yet (pose_source.localization_pending), hold there up to ~anchor_wait s, then fail
        (TaskError) saying why. Why: with no GNSS indoors a robot that goes in before its SLAM pose is
        anchored has no trusted pose inside (source none) and every goal there fails at once (explore +
        GNSS-denied mission, seed 101 on 17b1e7b: the UGV through its door 2 s after the start, its SLAM stack
        lagging at the start-up's load; it stood inside for the whole trial). Without a localization (no
        `indoor_slam`) nothing waits."""
        end = self.backend.now() + self.p.anchor_wait
        said = False
        while True:
            with self.state_lock:
                pending = self.pose_source.localization_pending(self.backend.now())
            if not pending:
                if said:
                    self.backend.loginfo(f'[{task.name}] the indoor localization is anchored: going in')
                return
            if self.backend.now() >= end:
                raise TaskError(f'{what}: the indoor localization is not anchored after '
                                f'{self.p.anchor_wait:.0f} s: not going in')
            if not said:
                self.backend.logwarn(f'[{task.name}] {what}: waiting for the indoor localization to be anchored')
                said = True
            task.feedback('WAITING', f'{what}: for the indoor localization to be anchored')
            task.check_preempt()
            self.backend.sleep(1.0 / C.CONTROL_RATE_HZ)

    def raise_if_lost(self, what: str = '') -> None:
        """TaskError when no pose is trusted (pose source none): the robot holds, the central unit reassigns."""
        if not self.pose_source.valid:
            raise TaskError(f'{what + ": " if what else ""}no trusted pose ({self.pose_source.why}): holding')

    def set_point_z(self, target: Sequence[float]) -> float:
        """The z a go-to to target is flown to (a UAV's clearance guard may raise it)."""
        return float(target[2])

    def hold(self) -> None:
        """Stop where the robot is (a waypoint at the current pose); quiet if that fails."""
        try:
            p = self.position(wait=0.0)
            if self.is_moving_state():
                self.send_waypoint(p[0], p[1], p[2], p[3])
        except Exception as e:
            self.backend.logerr_throttle(2.0, f'hold failed: {e}')

    def is_moving_state(self) -> bool:
        """True when the UAL accepts motion commands (flying UAV / any UGV)."""
        return self.ual_state in (C.UAL_FLYING_AUTO, C.UAL_FLYING_MANUAL)

    def send_velocity(self, v: Sequence[float], yaw_rate: float = 0.0) -> None:
        """ual/set_velocity in the arena frame (the UAL stops the robot 0.5 s after the last one); while a GNSS
        jump is doubted: a hold (zero velocity). Not while no pose is trusted: the velocity loops are the
        laser-guided ones (see _on_pose_lost), and a shift of the frames changes no velocity."""
        if self.pose_doubt_since is not None:
            self._hold_still()
            return
        with self._set_point_lock:
            self._set_point = None              # the UAL follows velocities now
        msg = TwistStamped()
        msg.header.stamp = self._stamp()
        msg.header.frame_id = C.GLOBAL_FRAME
        msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z = (float(v[0]), float(v[1]), float(v[2]))
        msg.twist.angular.z = float(yaw_rate)
        self.vel_pub.publish(msg)

    # ---- regions ----------------------------------------------------------------------------------------
    def _region_request(self, label: str, box: Box) -> AskForRegionRequest:
        """The AskForRegion request of our box under label (arena frame)."""
        req = AskForRegionRequest(agent_id=self.agent_id, label=label)
        for name, corner in (('min_corner', box[0]), ('max_corner', box[1])):
            point = PointStamped()
            point.header.frame_id = C.GLOBAL_FRAME
            point.point.x, point.point.y, point.point.z = (float(v) for v in corner)
            setattr(req, name, point)
        return req

    def pose_error_pad(self, label: str, over_pad: bool = False) -> np.ndarray:
        """m (x, y, z) our box `label` is grown by on each side for the error of our reported pose."""
        return pose_error_pad(label, self.p.pose_error_margin, self.p.pose_error_margin_z, over_pad)

    def _ask(self, label: str, box: Box, over_pad: bool = False, as_held: bool = False) -> tuple:
        """One ask_for_region of box grown by our pose error (pose_error_boxes.py; over_pad: x, y are a
        pad's; as_held: box is already as the manager holds it, e.g. a held box moved): (granted, why not);
        a granted box is remembered in `held` as the manager holds it."""
        if not as_held:
            box = grown(box, self.pose_error_pad(label, over_pad))
        try:
            if not self.ask_srv(self._region_request(label, box)).success:
                return False, 'occupied by another agent'
        except Exception as e:
            return False, f'ask_for_region failed: {e}'
        with self._regions_lock:
            self.held[label] = (np.asarray(box[0], float), np.asarray(box[1], float))
        return True, ''

    def reserve(self, task: AgentTask, label: str, box: Any, timeout: Optional[float] = None,
                over_pad: bool = False, as_held: bool = False) -> None:
        """Ask for box under label until granted (2 Hz); TaskError after timeout s.

        While it waits, the region manager may ask this robot to step aside out of another robot's
        refused box (a deadlock, `_on_yield_region`): the step is taken here, in the task's thread, and
        the box asked for grows to cover the path from the new place (the robot now starts from there)."""
        if not self.p.use_regions:
            return
        box = make_box(*box)
        timeout = self.p.region_timeout if timeout is None else timeout
        end = self.backend.now() + timeout
        try:
            while True:
                task.check_preempt()
                ok, why = self._ask(label, box, over_pad, as_held)
                if ok:
                    return
                with self._regions_lock:
                    self._waiting_for = label
                    order, self._yield_order = self._yield_order, None
                if order is not None and self._step_aside(task, *order):
                    box = self._covering_here(box)
                    continue
                if self.backend.now() > end:
                    raise TaskError(f'region {label} not granted after {timeout:.0f} s ({why})')
                task.feedback('WAITING_REGION', f'waiting for region {label}: {why}')
                self.backend.sleep(0.5)
        finally:
            with self._regions_lock:
                self._waiting_for, self._yield_order = None, None

    def free(self, label: str = '', free_all: bool = False) -> None:
        """Free one region (or all of ours); errors are only logged (the manager may be gone)."""
        if not self.p.use_regions:
            return
        with self._regions_lock:
            if free_all:
                self.held.clear()
            else:
                self.held.pop(label, None)
        try:
            self.free_srv(FreeRegionsRequest(agent_id=self.agent_id, label=label, free_all=free_all))
        except Exception as e:
            self.backend.logerr_throttle(5.0, f'free_regions failed: {e}')

    def hold_box(self, p: Sequence[float]) -> Box:
        """The box a hovering UAV keeps for itself around p."""
        h = self.p.hold_half_size
        return (np.array([p[0] - h, p[1] - h, p[2] - h]), np.array([p[0] + h, p[1] + h, p[2] + h]))

    def _covering_here(self, box: Box) -> Box:
        """box grown to cover the robot's place (as a go-to leg's start is covered): after a step aside
        the path to the box starts from here."""
        here = self.position(wait=0.0)[:3]
        pad = max(self.p.hold_half_size, self.p.region_margin)
        return np.minimum(box[0], here - pad), np.maximum(box[1], here + pad)

    # ---- deadlocks: stepping aside when the region manager asks ------------------------------------------
    def _on_yield_region(self, req: Any) -> AskForRegionResponse:
        """yield_region: the region manager found a deadlock (each of two robots waits for a box that
        overlaps the other's hold) and asks this robot to leave req's box, the refused request of robot
        req.agent_id. Accepted (success) only while a task waits in reserve() for another box, hovering,
        with nothing but the hover box in the way and a place to step to; the step is taken by the
        waiting task (reserve). Declined otherwise: the manager then asks the other robot."""
        lo = (req.min_corner.point.x, req.min_corner.point.y, req.min_corner.point.z)
        hi = (req.max_corner.point.x, req.max_corner.point.y, req.max_corner.point.z)
        what = f'{req.agent_id}/{req.label} {box_text((lo, hi))}'
        if not all(map(math.isfinite, lo + hi)):
            self.backend.logerr_throttle(5.0, f'yield_region from {req.agent_id!r}: NaN or infinite box')
            return AskForRegionResponse(success=False)
        box = make_box(lo, hi)
        why = self._why_cannot_yield(box)
        if why:
            self.backend.logwarn(f'region manager asks us to step out of {what}: declined ({why})')
            return AskForRegionResponse(success=False)
        with self._regions_lock:
            self._yield_order = (str(req.agent_id), str(req.label), box)
        self.backend.logwarn(f'region manager asks us to step out of {what} (a deadlock): accepted')
        return AskForRegionResponse(success=True)

    def _why_cannot_yield(self, box: Box) -> str:
        """Why this robot cannot step out of box now ('' when it can)."""
        if self.ROBOT_TYPE != 'uav' or not self.p.use_regions:
            return 'not a UAV reserving regions'
        if self.ual_state != C.UAL_FLYING_AUTO or self.pose is None or self.pose_in_doubt():
            return 'not hovering with a trusted pose'
        with self._regions_lock:
            waiting, held = self._waiting_for, dict(self.held)
        if waiting == 'hold' or (waiting is None and self.running_task()):
            return 'busy, not waiting for a region'          # (it frees its boxes when its work ends)
        in_the_way = sorted(l for l, b in held.items() if boxes_overlap(b, box))
        if in_the_way != ['hold']:
            return f'our boxes in the way: {in_the_way or "none"}'
        if not self._step_moves(box):
            return 'no free place to step to'
        return ''

    def _step_moves(self, box: Box) -> list:
        """(target, step box, new hover box) of the steps out of box (region_yield.step_aside_moves): our hover
        box as the manager holds it, moved along one axis (over a pad it is not grown sideways)."""
        with self._regions_lock:
            held = self.held.get('hold')
        here = self.position(wait=0.0)
        if held is None:     # (not reached: a yield is accepted only with the hold in the way) grown here
            held = grown(self.hold_box(here), self.pose_error_pad('hold'))
        return step_aside_moves(here, held, box, self.arena, C.BUILDINGS,
                                self.p.building_clearance, self.p.step_aside_min_z, self.p.step_aside_max)

    def _step_aside(self, task: AgentTask, winner: str, label: str, box: Box) -> bool:
        """Move the hover box out of box (robot winner's refused request `label`): reserve the step (our
        hold to the new place), fly it, hold there. False (and a log) when no step is granted."""
        here = self.position()
        for target, step, new_hold in self._step_moves(box):
            if not self._ask(STEP_LABEL, step, as_held=True)[0]:
                continue
            self.backend.logwarn(f'stepping aside from {np.round(here[:3], 2)} to {np.round(target, 2)}: out of '
                                 f'{winner}/{label} {box_text(box)} (a deadlock)')
            task.feedback('STEPPING_ASIDE', f'out of the way of {winner}/{label}')
            # the step box is freed only once the hold is ours where the UAV stopped: a step cut short
            # (preempted, timed out) leaves the UAV inside boxes it holds
            self.move_to(task, target, None, 'stepping aside')
            self.reserve(task, 'hold', new_hold, timeout=10.0, as_held=True)
            self.free(STEP_LABEL)
            return True
        self.backend.logwarn(f'cannot step out of {winner}/{label} {box_text(box)}: no step granted')
        return False

    # ---- payload ---------------------------------------------------------------------------------------
    def trigger(self, srv: Any, what: str) -> None:
        """Call a std_srvs/Trigger actuator; TaskError when it fails."""
        try:
            res = srv()
        except Exception as e:
            raise TaskError(f'{what} failed: {e}')
        if not res.success:
            raise TaskError(f'{what} refused: {res.message}')

    def start_pump(self) -> None:
        """Start shooting water."""
        self.trigger(self.pump_start_srv, 'start_pump')
        self.pumping = True

    def stop_pump(self) -> None:
        """Stop shooting water (never raises: it is called on the way out of errors)."""
        self.pumping = False
        try:
            self.pump_stop_srv()
        except Exception as e:
            self.backend.logerr_throttle(2.0, f'stop_pump failed: {e}')

    def fire_detected(self) -> Optional[bool]:
        """The thermal camera's CheckFire answer (None when the detector does not answer)."""
        try:
            return bool(self.check_fire_srv().fire_detected)
        except Exception as e:
            self.backend.logerr_throttle(5.0, f'thermal_detection/fire_detected failed: {e}')
            return None

    def set_object_status(self, object_id: int, status: int) -> None:
        """Tell the estimator a fire's new status (errors are only logged)."""
        try:
            self.status_srv(SetObjectStatusRequest(object_id=int(object_id), object_status=int(status),
                                                   object_type=C.TYPE_FIRE))
        except Exception as e:
            self.backend.logerr_throttle(5.0, f'set_object_status failed: {e}')

    def water_empty(self) -> bool:
        """True when the flow meter says the tank is (nearly) empty."""
        return math.isfinite(self.water_level) and self.water_level <= self.p.water_empty

    # ---- framework hooks -------------------------------------------------------------------------------
    def safe_stop(self) -> None:
        """After a failed or preempted task: pump off, stop where we are, keep only a hover box there."""
        if self.pumping or self.p.payload == 'water':
            self.stop_pump()
        self.hold()
        self._keep_only_a_hover_box()

    def _keep_only_a_hover_box(self) -> None:
        """A flying UAV whose task failed or was preempted holds a hover box where it is and frees the way it
        was flying (go_to, a step...): the way stays reserved otherwise until its next task, and an idle UAV
        declines to step aside from it. Why (realistic seed 110): go_home failed 1.3 m short of the pad's
        column, the blanket UAV hovered idle 900 s with its go_to box, and both other UAVs' take-offs were
        refused to the end. When the hover box is refused, everything is kept (never fly unreserved)."""
        if self.ROBOT_TYPE != 'uav' or not self.p.use_regions or self.ual_state != C.UAL_FLYING_AUTO:
            return
        with self._regions_lock:
            ways = [label for label in self.held if label not in ('hold', 'parked')]
        if not ways:
            return
        here = self.position(wait=0.0)
        if not self._ask('hold', self.hold_box(here))[0]:
            return
        for label in ways:
            self.free(label)

    def ground_anchor(self, p: Sequence[float]) -> tuple:
        """(x, y) of the boxes a landed UAV reserves (parked box, take-off column): its home pad when it
        stands within C.HOME_PAD_RADIUS of it, else where it reports to be.

        Why: the reported pose of a landed UAV wanders with the GNSS bias (a metre, slowly) while the UAV
        stands still; boxes placed on it drift into the next pad's column, 3.3 m away. Seen under realistic
        uncertainty: a refilled UAV waited minutes for its take-off column, refused because of the parked
        box of its landed neighbour. The pads' places are known before the trial and do not wander."""
        if self.home is not None and math.hypot(p[0] - self.home[0], p[1] - self.home[1]) <= C.HOME_PAD_RADIUS:
            return float(self.home[0]), float(self.home[1])
        return float(p[0]), float(p[1])

    def idle(self) -> None:
        """While idle and landed, keep a 'parked' box so that no other UAV flies low over this one, and nothing
        else; while idle and hovering, step aside when the region manager asked (a robot waits long for our
        hold); while idle with no trusted pose, keep off the walls by the laser."""
        self._keep_off_walls_without_pose()
        if self.ROBOT_TYPE != 'uav' or not self.p.use_regions:
            return
        self._idle_step_aside()
        if self.ual_state not in (C.UAL_LANDED_DISARMED, C.UAL_LANDED_ARMED) or self.pose is None:
            return
        self._free_the_boxes_of_flight()
        if self.parked:
            return
        now = self.backend.now()
        if now - self._last_park_try < 2.0:
            return
        self._last_park_try = now
        p, h = self.position(wait=0.0), self.p.parked_half_size
        p = (*self.ground_anchor(p), p[2])
        # up to parked_height above the ground it stands on, not above its reported (GNSS) height
        box = ((p[0] - h, p[1] - h, self.arena[2]), (p[0] + h, p[1] + h, self.arena[2] + self.p.parked_height))
        self.parked = self._ask('parked', box)[0]   # no region manager (yet): tried again later

    def _keep_off_walls_without_pose(self) -> None:
        """Idle, moving (a flying UAV, a UGV) and with no trusted pose (pose source none): with ~wall_clearance,
        off the walls the latest fresh scan shows nearer than ~min_wall_clearance, by velocity (wall_clearance.away_velocity:
        the returns about the robot and the compass's yaw, no position), then a hold; clear of the walls and
        lost for ~lost_back_out_after s, back out the way it came (way_back.py), then a hold. Why: a task that
        failed for want of a pose leaves the robot holding on the UAL's own pose, which indoors dead-reckons
        and drifts; a UAV held in a room that way hit the building 142 s later (realistic seed 105 with no GNSS
        indoors, mbzirc_launchers README). The central unit sends no goal while the data_feed says the pose is
        lost (NO_TRUSTED_POSE)."""
        if self.pose_source.valid or not self.is_moving_state() or self.pose is None:
            self._backing_off_blind = False
            return
        scan = self._scan
        if scan is None or self.backend.now() - scan[1] > C.SCAN_MAX_AGE:
            return
        msg = scan[0]
        points = scan_points(msg.ranges, msg.angle_min, msg.angle_increment, (0.0, 0.0, 0.0, float(self.pose[3])),
                             msg.range_min, msg.range_max if msg.range_max > 0 else math.inf, keep_near=True)
        v = None
        if self.p.wall_clearance:
            v = away_velocity(points, self.p.min_wall_clearance, self.p.wall_clearance_margin,
                              C.BLIND_BACK_OFF_GAIN, C.BLIND_BACK_OFF_SPEED)
        v_is_back_out = v is None
        if v is None:
            v = self._back_out_velocity(points)
        if v is None:
            if self._backing_off_blind:
                self.send_velocity((0.0, 0.0, 0.0))      # off the wall, or at the way back's end: hold there
                self._backing_off_blind = False
            return
        if not self._backing_off_blind:
            self.backend.logwarn(f'no trusted pose ({self.pose_source.why}): '
                                 + ('backing out the way it came' if v_is_back_out else
                                    f'a wall nearer than {self.p.min_wall_clearance:.2f} m by the laser: moving off it'))
        self._backing_off_blind = True
        self.send_velocity((float(v[0]), float(v[1]), 0.0))

    def _back_out_velocity(self, points: np.ndarray) -> Optional[np.ndarray]:
        """The velocity back along the way in (way_back.py), once lost for ~lost_back_out_after s; None
        before, and at its end (said once)."""
        after = self.p.lost_back_out_after
        lost_since = self._lost_since
        if after <= 0 or lost_since is None or self.backend.now() - lost_since < after or self.way_back.done:
            return None
        p = self.p

        def blocked(u) -> bool:
            return wall_ahead(points, (0.0, 0.0), u, p.leg_guard_half_width, p.leg_guard_stop_distance) is not None
        v = self.way_back.velocity(self.position(wait=0.0), blocked)
        where = self.way_back.take_end()
        if where is not None:
            self.backend.logwarn(f'no trusted pose ({self.pose_source.why}): backed out the way it came as far as '
                                 f'{where}: holding')
        return v

    def _free_the_boxes_of_flight(self) -> None:
        """A landed idle UAV frees every box but its parked one. Why (realistic seed 102): a landing preempted
        half-way goes on (the UAL cannot hold a landing), the task ends with its 'land' column and hover box
        reserved, and the next go-home, finding the UAV landed, skips the landing that would free them: the
        other UAVs' legs through that column were refused for 230 s."""
        with self._regions_lock:
            flying = [label for label in self.held if label != 'parked']
        for label in flying:
            self.free(label)

    def _idle_step_aside(self) -> None:
        """The step out of a waiting robot's box that the region manager asked of this idle UAV (no task
        waits in reserve() to take it: the idle loop does). Why: the manager's cycle rule never fires when
        the holder waits for nothing, and a UAV hovering with no work would block the other for good."""
        with self._regions_lock:
            order, self._yield_order = self._yield_order, None
        if order is None or self.ual_state != C.UAL_FLYING_AUTO:
            return
        try:
            self._step_aside(IdleStep(self), *order)
        except Exception as e:          # TaskError (not there, no hold granted), a crash: logged, idle again
            self.backend.logwarn(f'stepping aside while idle failed: {e}')

    def _on_cost(self, req: Any) -> GetCostToGoToResponse:
        """get_cost_to_go_to: metres to travel (-1 when the waypoint is invalid or unreachable)."""
        try:
            p = req.waypoint.pose.position
            target = (p.x, p.y, p.z)
            self.check_point(target)
            return GetCostToGoToResponse(cost=float(self.cost_to_go_to(target)))
        except (ValueError, TaskError) as e:
            self.backend.logerr_throttle(5.0, f'get_cost_to_go_to: {e}')
            return GetCostToGoToResponse(cost=-1.0)

    def cost_to_go_to(self, target: Sequence[float]) -> float:
        """Straight-line distance (UAV); the UGV plans around the building."""
        return float(np.linalg.norm(np.asarray(target) - self.position(wait=0.0)[:3]))


class IdleStep:
    """The task stand-in of a step aside taken by the idle loop: nothing to preempt (a goal that arrives
    meanwhile starts once the short step is done), its feedback only logged."""

    def __init__(self, agent: 'RobotAgent') -> None:
        self.agent = agent
        self.name = 'idle'

    def check_preempt(self) -> None:
        """Never preempted; the state machine's loop still shows it runs (the agent's liveness)."""
        self.agent.note_sm_alive()

    def feedback(self, state: str, text: str) -> None:
        self.agent.backend.loginfo_throttle(2.0, f'[idle] {state}: {text}')
