"""ROS adapter of the simulator: one node serves /clock, every robot's UAL interface, sensors, TF and /sim/*.

One loop in the main thread steps the physics at `~sim_rate` in sim time, paced to `~rtf` x wall time, and
publishes what is due and subscribed (sensors cost nothing when nobody listens). Service calls arrive on
rospy's threads and take `sim.lock`; blocking UAL calls wait (in wall time) until the robot gets there.
Topic names are relative, so the node can be pushed into a namespace.
"""
from __future__ import annotations

import math
import time
from typing import Callable, Optional

import numpy as np
import rospy
from rospy.numpy_msg import numpy_msg
from geometry_msgs.msg import Point, Pose, PoseArray, PoseStamped, Quaternion, TransformStamped, TwistStamped, Vector3
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, LaserScan, NavSatStatus, Range
from std_msgs.msg import Bool, Float32, Float64, Float64MultiArray, Header, MultiArrayDimension
from std_srvs.srv import Empty, EmptyResponse, Trigger, TriggerResponse
from tf2_msgs.msg import TFMessage
from uav_abstraction_layer.msg import State
from uav_abstraction_layer.srv import (GoToWaypoint, GoToWaypointResponse, Land, LandResponse, SetHome,
                                       SetHomeResponse, TakeOff, TakeOffResponse)
from visualization_msgs.msg import MarkerArray

from ual_sim.msg import FireState, FireStateArray, Score, WaterAccount, WaterUse
from ual_sim.srv import InjectFault, InjectFaultResponse

from . import constants as C
from .markers import build_markers
from .effects import WaterLedger
from .robot import Robot
from .sim import Simulation
from .thermal import DOWNWARD, FORWARD, to_rgb
from .uncertainty import UncertaintyError, profile as uncertainty_profile, with_gnss_denied_indoors
from .world import WorldError, load_world

Q = 10  # publisher queue size: rospy then writes to sockets from its own threads, not from the sim loop


_last_err: dict = {}


def logerr_throttled(key: str, period: float, text: str) -> None:
    """rospy.logerr at most once per `period` wall seconds per key (rospy's throttle is per source line and
    counts sim time, so at 10x it would flood, and one robot's error would hide another's)."""
    now = time.monotonic()
    if now - _last_err.get(key, -1e9) >= period:
        _last_err[key] = now
        rospy.logerr(text)


def set_point(p, x: float, y: float, z: float) -> None:
    """Fill a Point / Vector3 in place (no new message object per tick)."""
    p.x, p.y, p.z = x, y, z


def yaw_quat(yaw: float) -> Quaternion:
    return Quaternion(0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


def quat_yaw(q: Quaternion) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def water_account(ledger: WaterLedger, header: Header) -> WaterAccount:
    """/sim/water: the ledger of where each robot's water went, one WaterUse per robot that has pumped."""
    fires = ledger.fires.fires
    msg = WaterAccount(header=header)
    for rid, use in sorted(ledger.robots.items()):
        m = WaterUse(robot_id=rid, litres_pumped=use.pumped, litres_into_fires=use.into_fires,
                     litres_on_walls=use.on_walls, litres_fell_short=use.fell_short)
        pours = sorted(use.pours.items(), key=lambda kv: -1 if kv[0] is None else kv[0])
        m.holder_ids = ["" if i is None else fires[i].holder.id for i, _ in pours]
        m.holder_kinds = [WaterUse.NO_HOLDER if i is None else fires[i].kind for i, _ in pours]
        m.aimed, m.entered = [p.aimed for _, p in pours], [p.entered for _, p in pours]
        m.on_wall, m.fell_short = [p.on_wall for _, p in pours], [p.fell_short for _, p in pours]
        msg.robots.append(m)
    return msg


class Due:
    """A periodic output in sim time (next due time advances by whole periods, so rates hold on average)."""

    def __init__(self, rate: float, phase: float = 0.0):
        self.period = 1.0 / rate if rate > 0 else math.inf
        self.next = phase * self.period

    def __call__(self, now: float) -> bool:
        if now + 1e-9 < self.next:
            return False
        self.next += self.period * max(1.0, math.floor((now - self.next) / self.period) + 1.0)
        return True


def paced_origin(wall0: float, ahead: float, catch_up_limit: float) -> float:
    """The wall-clock origin of the pacing, given `ahead` (wall s the simulation is ahead of its real-time
    factor; negative: behind): when it is more than `catch_up_limit` wall s behind, the origin moves so that
    it is exactly that much behind, and the rest of the lag is dropped (the factor achieved falls) instead of
    being caught up in a burst of ticks.
    Why: a burst runs simulated seconds in a fraction of a wall second, during which no other node can act:
    with a limit of 1 s at 4x real time, a loaded machine ran 3.2 sim-s in 0.14 wall-s while a UAV crossed a
    window, its agent's last velocity command timed out, the UAV hovered uncorrected in the gusts and hit the
    frame (passage_realistic.test in a loaded CI run). A real robot's time does not jump."""
    if ahead < -catch_up_limit:
        return wall0 - (ahead + catch_up_limit)
    return wall0


class AtMostPerWallSecond:
    """True at most `rate` times a wall second (rate <= 0: always); for outputs whose cost is per message
    and whose receivers only need the latest one (/clock)."""

    def __init__(self, rate: float, clock: Callable[[], float] = time.monotonic):
        self.period = 1.0 / rate if rate > 0 else 0.0
        self.clock = clock
        self.next = -math.inf

    def __call__(self) -> bool:
        now = self.clock()
        if now < self.next:
            return False
        # the rate holds on average (not one message every whole number of ticks), without a burst after
        # a stall
        self.next = (self.next if now - self.next < self.period else now) + self.period
        return True


class RobotIO:
    """Publishers, subscribers and services of one robot (namespace mbzirc2020_<id>)."""

    def __init__(self, node: "SimNode", r: Robot, k: int):
        self.node, self.r, self.rid = node, r, r.id
        self.pending_velocity: Optional[tuple] = None    # (v, frame_id) of the last set_velocity not yet applied
        ns = C.robot_ns(r.id)
        self.ns = ns
        self.frame = f"{ns}/base_link"
        sim = node.sim
        p = lambda name, typ, latch=False: rospy.Publisher(f"{ns}/{name}", typ, queue_size=Q, latch=latch)  # noqa: E731
        self.pub_pose = p("ual/pose", PoseStamped)
        self.pub_vel = p("ual/velocity", TwistStamped)
        self.pub_odom = p("ual/odom", Odometry)
        # latched: published when the state changes (and every STATE_KEEPALIVE_S), a late subscriber still
        # gets the current state at once
        self.pub_state = p("ual/state", State, latch=True)
        # latched like ual/state: STATUS_FIX while the reported pose follows GNSS, STATUS_NO_FIX indoors
        # when the world has no GNSS there (the pose dead-reckons and drifts; README "No GNSS indoors")
        self.pub_gnss = p("ual/gnss_status", NavSatStatus, latch=True)
        self.pub_water = p("actuators_system/water_level", Float32)
        self.pub_blanket = p("actuators_system/blanket_attached", Bool)
        self.has_laser = node.params["laser"]
        self.thermal_dir = DOWNWARD if r.spec.payload == C.PAYLOAD_BLANKET else FORWARD
        self.has_thermal = node.params["thermal"]
        self.has_rgbd = node.params["rgbd"] and r.spec.payload == C.PAYLOAD_WATER
        self.has_altimeter = r.is_uav
        if self.has_altimeter:
            self.pub_alt = p("altimeter", Range)
            self.m_alt = Range(radiation_type=Range.INFRARED, field_of_view=C.ALTIMETER_FOV,
                               min_range=C.ALTIMETER_RANGE_MIN, max_range=C.ALTIMETER_RANGE_MAX)
            self.m_alt.header.frame_id = f"{ns}/altimeter_link"
        if self.has_laser:
            self.pub_scan = p("scan", numpy_msg(LaserScan))     # arrays serialised with tobytes()
        if self.has_thermal:
            self.pub_traw = p("teraranger_evo_thermal/raw_temp_array", numpy_msg(Float64MultiArray))
            self.pub_trgb = p("teraranger_evo_thermal/rgb_image", Image)
            self.pub_tptat = p("teraranger_evo_thermal/ptat", Float64)
        if self.has_rgbd:
            self.pub_color = p("camera/color/image_rect_color", Image)
            self.pub_depth = p("camera/aligned_depth_to_color/image_raw", Image)
            self.pub_cinfo = p("camera/color/camera_info", CameraInfo)
            self.pub_dinfo = p("camera/aligned_depth_to_color/camera_info", CameraInfo)
        n = max(1, len(sim.robots))
        self.due_pose = Due(node.params["pub_rate"], k / n)
        self.due_laser = Due(node.params["laser_rate"], k / n)
        self.due_thermal = Due(node.params["thermal_rate"], (k + 0.5) / n)
        self.due_rgbd = Due(node.params["rgbd_rate"], k / n)
        self.due_actuators = Due(2.0, k / n)
        self.due_altimeter = Due(C.ALTIMETER_RATE, k / n)
        s = lambda name, typ, cb: rospy.Service(f"{ns}/{name}", typ, cb)  # noqa: E731
        self.services = [
            s("ual/take_off", TakeOff, self.on_take_off), s("ual/land", Land, self.on_land),
            s("ual/go_to_waypoint", GoToWaypoint, self.on_go_to), s("ual/set_home", SetHome, self.on_set_home),
            s("ual/recover_from_manual", Empty, self.on_recover),
            s("actuators_system/start_pump", Trigger, lambda _: self.trigger(sim.start_pump)),
            s("actuators_system/stop_pump", Trigger, lambda _: self.trigger(sim.stop_pump)),
            s("actuators_system/release_blanket", Trigger, lambda _: self.trigger(sim.release_blanket)),
        ]
        self.subs = [rospy.Subscriber(f"{ns}/ual/set_velocity", TwistStamped, self.on_set_velocity, queue_size=1),
                     rospy.Subscriber(f"{ns}/ual/set_pose", PoseStamped, self.on_set_pose, queue_size=1)]
        # reusable messages (rospy serialises in publish(), so they can be filled again at the next tick)
        self.m_pose, self.m_vel, self.m_odom, self.m_state = PoseStamped(), TwistStamped(), Odometry(), State()
        self.m_pose.header.frame_id = self.m_vel.header.frame_id = self.m_odom.header.frame_id = C.FRAME_ARENA
        self.m_odom.child_frame_id = self.frame
        self.m_tf = TransformStamped()
        self.m_tf.header.frame_id = f"{ns}/odom" if node.params["tf_odom"] else C.FRAME_ARENA
        self.m_tf.child_frame_id = self.frame
        self.state_sent = (None, -math.inf)    # state and sim time of the last ual/state
        self.gnss_sent = (None, -math.inf)     # GNSS validity and sim time of the last ual/gnss_status

    # ------------------------------------------------------------------ services
    def _log_refusal(self, what: str, msg: str) -> None:
        rospy.logerr(f"[ual_sim] {self.ns} {what}: {msg}")

    def _comm(self, what: str) -> bool:
        if not self.r.comm_ok(self.node.sim.time):
            logerr_throttled(self.ns + "comm", 2.0, f"[ual_sim] {self.ns}: {what} ignored (communication lost)")
            return False
        return True

    def _command(self, what: str, fn: Callable[[], tuple[bool, str]], blocking: bool) -> bool:
        if not self._comm(what):
            return False
        self.pending_velocity = None          # a velocity received before this command is older than it
        with self.node.sim.lock:
            ok, msg = fn()
        if not ok:
            self._log_refusal(what, msg)
            return False
        if blocking:
            self.node.wait_for(self.r)
        return True

    def on_take_off(self, req) -> TakeOffResponse:
        self._command("take_off", lambda: self.r.take_off(float(req.height)), req.blocking)
        return TakeOffResponse()

    def on_land(self, req) -> LandResponse:
        self._command("land", self.r.land, req.blocking)
        return LandResponse()

    def on_go_to(self, req) -> GoToWaypointResponse:
        wp = req.waypoint
        frame = wp.header.frame_id.lstrip("/")
        if frame not in ("", C.FRAME_ARENA, "map", "odom", f"{self.ns}/odom"):
            self._log_refusal("go_to_waypoint", f"unsupported frame_id '{wp.header.frame_id}' (use '{C.FRAME_ARENA}')")
            return GoToWaypointResponse()
        p, q = wp.pose.position, wp.pose.orientation
        qn = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
        yaw = quat_yaw(q) if qn > 1e-6 else self.r.yaw
        self._command("go_to_waypoint", lambda: self.r.go_to(p.x, p.y, p.z, yaw), req.blocking)
        return GoToWaypointResponse()

    def on_set_home(self, req) -> SetHomeResponse:
        if self._comm("set_home"):
            with self.node.sim.lock:
                self.r.set_home(bool(req.set_z))
        return SetHomeResponse()

    def on_recover(self, _req) -> EmptyResponse:
        if self._comm("recover_from_manual"):
            with self.node.sim.lock:
                self.r.recover_from_manual()
        return EmptyResponse()

    def trigger(self, fn: Callable[[int], tuple[bool, str]]) -> TriggerResponse:
        if not self.r.comm_ok(self.node.sim.time):
            return TriggerResponse(False, "communication lost")
        with self.node.sim.lock:
            ok, msg = fn(self.rid)
        if not ok:
            logerr_throttled(self.ns + "act" + msg, 1.0, f"[ual_sim] {self.ns} actuator: {msg}")
        return TriggerResponse(ok, msg)

    def on_set_velocity(self, msg: TwistStamped) -> None:
        """Kept for the sim loop's next tick (apply_velocity), not applied here under sim.lock. Why: while the
        sim runs behind its real-time factor its loop re-takes the lock at once after each tick, and this
        callback's thread can wait for it long (a stand-alone model of that loop on a loaded machine: up to
        0.22 s of wall time, 1-2 s of sim time at 4-8x): the velocity command times out (VELOCITY_CMD_TIMEOUT)
        and the robot falls back to its position hold, which follows the GNSS error, although the commands
        come 7 times a second (realistic seed 101 at RTF 4: a UAV in a window's wall held its GNSS position for
        3 s, true y still, while its recorded commands, on time, said 0.8 m/s forward)."""
        if not self._comm("set_velocity"):
            return
        lin, ang = msg.twist.linear, msg.twist.angular
        self.pending_velocity = (np.array([lin.x, lin.y, lin.z, ang.z], dtype=float), msg.header.frame_id)

    def apply_velocity(self) -> None:
        """The last set_velocity received since the previous tick, if any (the sim loop, under sim.lock)."""
        pending, self.pending_velocity = self.pending_velocity, None
        if pending is None:
            return
        v, frame_id = pending
        if frame_id.endswith("base_link"):
            c, s = math.cos(self.r.yaw), math.sin(self.r.yaw)
            v[0], v[1] = c * v[0] - s * v[1], s * v[0] + c * v[1]
        ok, err = self.r.set_velocity(v, self.node.sim.time)
        if not ok:
            logerr_throttled(self.ns + "vel", 1.0, f"[ual_sim] {self.ns} set_velocity: {err}")

    def on_set_pose(self, msg: PoseStamped) -> None:
        if not self._comm("set_pose"):
            return
        p, q = msg.pose.position, msg.pose.orientation
        qn = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
        with self.node.sim.lock:
            yaw = quat_yaw(q) if qn > 1e-6 else self.r.yaw
            ok, err = self.r.go_to(p.x, p.y, p.z, yaw)
        if not ok:
            logerr_throttled(self.ns + "pose", 1.0, f"[ual_sim] {self.ns} set_pose: {err}")

    # ------------------------------------------------------------------ outputs
    def publish(self, now: float, stamp: rospy.Time) -> Optional[TransformStamped]:
        """Publish what is due and subscribed; returns the TF of this robot when its pose is due."""
        sim, r = self.node.sim, self.r
        if not r.comm_ok(now):
            return None
        tf = None
        if self.due_pose(now):
            x, y, z, yaw = sim.reported_pose(r)
            vel = sim.reported_velocity(r)    # always: a subscriber may connect between two checks below
            q = yaw_quat(yaw)
            if self.pub_pose.get_num_connections():
                m = self.m_pose
                m.header.stamp = stamp
                set_point(m.pose.position, x, y, z)
                m.pose.orientation = q
                self.pub_pose.publish(m)
            if self.pub_vel.get_num_connections():
                m = self.m_vel
                m.header.stamp = stamp
                m.twist.linear = Vector3(*vel)
                m.twist.angular = Vector3(0.0, 0.0, r.yaw_rate)
                self.pub_vel.publish(m)
            if self.pub_odom.get_num_connections():
                m = self.m_odom
                m.header.stamp = stamp
                m.pose.pose.position = Point(x, y, z)
                m.pose.pose.orientation = q
                c, s = math.cos(yaw), math.sin(yaw)   # odom twist is in the child (body) frame
                m.twist.twist.linear = Vector3(c * vel[0] + s * vel[1], -s * vel[0] + c * vel[1], vel[2])
                m.twist.twist.angular = Vector3(0.0, 0.0, r.yaw_rate)
                self.pub_odom.publish(m)
            last_state, last_time = self.state_sent
            if (r.state != last_state or not last_time <= now < last_time + C.STATE_KEEPALIVE_S) \
                    and self.pub_state.get_num_connections():
                self.m_state.state = r.state
                self.pub_state.publish(self.m_state)
                self.state_sent = (r.state, now)
            self.publish_gnss_status(now)
            tf = self.m_tf
            tf.header.stamp = stamp
            set_point(tf.transform.translation, x, y, z)
            tf.transform.rotation = q
        if self.due_actuators(now):
            if self.pub_water.get_num_connections():
                self.pub_water.publish(Float32(r.water))
            if self.pub_blanket.get_num_connections():
                self.pub_blanket.publish(Bool(r.blanket))
        if not r.sensors_ok(now):
            return tf
        if self.has_altimeter and self.due_altimeter(now) and self.pub_alt.get_num_connections():
            self.m_alt.header.stamp = stamp
            self.m_alt.range = sim.altimeter(r)
            self.pub_alt.publish(self.m_alt)
        if self.has_laser and self.due_laser(now) and self.pub_scan.get_num_connections():
            self.node.timed("laser", lambda: self.publish_scan(stamp))
        if self.has_thermal and self.due_thermal(now) and (
                self.pub_traw.get_num_connections() or self.pub_trgb.get_num_connections()
                or self.pub_tptat.get_num_connections()):
            self.node.timed("thermal", lambda: self.publish_thermal(stamp))
        if self.has_rgbd and self.due_rgbd(now) and (
                self.pub_color.get_num_connections() or self.pub_depth.get_num_connections()
                or self.pub_cinfo.get_num_connections() or self.pub_dinfo.get_num_connections()):
            self.node.timed("rgbd", lambda: self.publish_rgbd(stamp))
        return tf

    def publish_gnss_status(self, now: float) -> None:
        """ual/gnss_status when the fix is lost or regained (logged) and every STATE_KEEPALIVE_S."""
        valid = self.node.sim.gnss_valid(self.r)
        last_valid, last_time = self.gnss_sent
        if valid != last_valid and last_valid is not None:
            rospy.loginfo(f"[ual_sim] t={now:.1f}s {self.ns}: GNSS {'fix regained' if valid else 'lost (indoors)'}")
        if (valid != last_valid or not last_time <= now < last_time + C.STATE_KEEPALIVE_S) \
                and self.pub_gnss.get_num_connections():
            status = NavSatStatus.STATUS_FIX if valid else NavSatStatus.STATUS_NO_FIX
            self.pub_gnss.publish(NavSatStatus(status=status, service=NavSatStatus.SERVICE_GPS))
            self.gnss_sent = (valid, now)
        elif valid != last_valid:
            self.gnss_sent = (valid, -math.inf)

    def publish_scan(self, stamp: rospy.Time) -> None:
        ranges = self.node.sim.laser(self.r)
        m = numpy_msg(LaserScan)()
        m.header.stamp, m.header.frame_id = stamp, f"{self.ns}/laser_link"
        m.angle_min = -math.pi
        m.angle_increment = 2.0 * math.pi / C.LASER_BEAMS
        m.angle_max = m.angle_min + m.angle_increment * (C.LASER_BEAMS - 1)
        m.scan_time = 1.0 / self.node.params["laser_rate"]
        m.time_increment = m.scan_time / C.LASER_BEAMS
        m.range_min, m.range_max = C.LASER_RANGE_MIN, C.LASER_RANGE_MAX
        m.ranges = ranges.astype(np.float32)
        m.intensities = np.zeros(0, np.float32)
        self.pub_scan.publish(m)

    def publish_thermal(self, stamp: rospy.Time) -> None:
        temps = self.node.sim.thermal_frame(self.r, self.thermal_dir)
        if self.pub_traw.get_num_connections():
            m = numpy_msg(Float64MultiArray)()
            m.layout.dim = [MultiArrayDimension("rows", C.THERMAL_SIZE, C.THERMAL_SIZE * C.THERMAL_SIZE),
                            MultiArrayDimension("cols", C.THERMAL_SIZE, C.THERMAL_SIZE)]
            m.data = np.ascontiguousarray(temps.ravel(), dtype=np.float64)
            self.pub_traw.publish(m)
        if self.pub_trgb.get_num_connections():
            img = to_rgb(temps)
            self.pub_trgb.publish(Image(header=Header(stamp=stamp, frame_id=f"{self.ns}/thermal_link"),
                                        height=C.THERMAL_SIZE, width=C.THERMAL_SIZE, encoding="rgb8",
                                        is_bigendian=0, step=3 * C.THERMAL_SIZE, data=img.tobytes()))
        if self.pub_tptat.get_num_connections():
            self.pub_tptat.publish(Float64(C.THERMAL_PTAT))

    def publish_rgbd(self, stamp: rospy.Time) -> None:
        cam = self.node.sim.rgbd
        frame = f"{self.ns}/camera_color_optical_frame"
        hdr = Header(stamp=stamp, frame_id=frame)
        want_c, want_d = self.pub_color.get_num_connections(), self.pub_depth.get_num_connections()
        if want_c or want_d:
            bgr, depth = self.node.sim.rgbd_frame(self.r)
            if want_c:
                self.pub_color.publish(Image(header=hdr, height=cam.h, width=cam.w, encoding="bgr8",
                                             is_bigendian=0, step=3 * cam.w, data=bgr.tobytes()))
            if want_d:
                self.pub_depth.publish(Image(header=hdr, height=cam.h, width=cam.w, encoding="16UC1",
                                             is_bigendian=0, step=2 * cam.w, data=depth.astype("<u2").tobytes()))
        info = cam.camera_info()
        ci = CameraInfo(header=hdr, height=cam.h, width=cam.w, distortion_model="plumb_bob",
                        D=[0.0] * 5, K=info["K"], R=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0], P=info["P"])
        if self.pub_cinfo.get_num_connections():
            self.pub_cinfo.publish(ci)
        if self.pub_dinfo.get_num_connections():
            self.pub_dinfo.publish(ci)

    def static_tfs(self, stamp: rospy.Time) -> list:
        """base_link -> laser_link, thermal_link, camera_color_optical_frame (REP 103 optical), and on a UAV
        altimeter_link (its x axis, the beam, pointing down)."""
        out = []

        def add(child: str, xyz, q: Quaternion, dz: float | None = None) -> None:
            t = TransformStamped()
            t.header.stamp, t.header.frame_id, t.child_frame_id = stamp, self.frame, f"{self.ns}/{child}"
            t.transform.translation = Vector3(xyz[0], xyz[1], xyz[2] + (self.r.sensor_z if dz is None else dz))
            t.transform.rotation = q
            out.append(t)
        add("laser_link", C.LASER_OFFSET, Quaternion(0, 0, 0, 1), self.r.laser_z)
        if self.thermal_dir == DOWNWARD:
            add("thermal_link", C.THERMAL_OFFSET_DOWNWARD, Quaternion(0, math.sqrt(0.5), 0, math.sqrt(0.5)))
        else:
            add("thermal_link", C.THERMAL_OFFSET_FORWARD, Quaternion(0, 0, 0, 1))
        add("camera_color_optical_frame", C.CAM_OFFSET, Quaternion(-0.5, 0.5, -0.5, 0.5))
        if self.has_altimeter:
            add("altimeter_link", (0.0, 0.0, 0.0), Quaternion(0, math.sqrt(0.5), 0, math.sqrt(0.5)), 0.0)
        return out


class SimNode:
    """The whole simulator node (see the package README for params and topics)."""

    def __init__(self):
        g = rospy.get_param
        self.params = {
            "world_file": str(g("~world_file", "")), "uavs": int(g("~uavs", 3)), "ugv": bool(g("~ugv", True)),
            "seed": int(g("~seed", 1)), "rtf": float(g("~rtf", 1.0)), "sim_rate": float(g("~sim_rate", C.SIM_RATE)),
            "pub_rate": float(g("~pub_rate", C.PUB_RATE)), "laser": bool(g("~laser", True)),
            "laser_rate": float(g("~laser_rate", C.LASER_RATE)), "thermal": bool(g("~thermal", True)),
            "thermal_rate": float(g("~thermal_rate", C.THERMAL_RATE)), "rgbd": bool(g("~rgbd", True)),
            "rgbd_rate": float(g("~rgbd_rate", C.CAM_RATE)), "pose_noise": float(g("~pose_noise", 0.0)),
            "wind": bool(g("~wind", True)), "tf_odom": bool(g("~tf_odom", False)),
            "markers": bool(g("~markers", True)), "uncertainty": str(g("~uncertainty", "ideal")),
            "clock_rate": float(g("~clock_rate", 0.0)),
            "catch_up_limit": max(0.0, float(g("~catch_up_limit", 0.1))),
            "gnss_denied_indoors": g("~gnss_denied_indoors", ""),
        }
        prm = self.params
        if not (prm["sim_rate"] > 0 and math.isfinite(prm["sim_rate"])):
            rospy.logerr(f"[ual_sim] ~sim_rate must be > 0, got {prm['sim_rate']}; using {C.SIM_RATE}")
            prm["sim_rate"] = C.SIM_RATE
        if prm["uavs"] < 0:
            rospy.logerr(f"[ual_sim] ~uavs must be >= 0, got {prm['uavs']}; using 3")
            prm["uavs"] = 3
        try:
            world = load_world(prm["world_file"] or None, n_uavs=prm["uavs"], ugv=prm["ugv"])
        except WorldError as e:
            rospy.logerr(f"[ual_sim] {e}. Falling back to the default world.")
            world = load_world(None, n_uavs=prm["uavs"], ugv=prm["ugv"])
        try:
            unc = uncertainty_profile(world.uncertainty, prm["uncertainty"])
        except UncertaintyError as e:
            rospy.logerr(f"[ual_sim] {e}. Using the ideal world (no uncertainty).")
            unc = uncertainty_profile({}, "ideal")
        unc = with_gnss_denied_indoors(unc, self._denied_indoors_override(prm["gnss_denied_indoors"]))
        self.sim = Simulation(world, prm["seed"], prm["pose_noise"], prm["wind"], unc)
        self._log_unknowns(unc.name)
        self.own_clock = self._stop_listening_to_own_clock()
        self.cpu: dict[str, list[float]] = {}
        self.pub_clock = rospy.Publisher("/clock", Clock, queue_size=Q)
        self.pub_tf = rospy.Publisher("/tf", TFMessage, queue_size=Q)
        self.pub_tf_static = rospy.Publisher("/tf_static", TFMessage, queue_size=Q, latch=True)
        self.pub_fires = rospy.Publisher("/sim/fires", FireStateArray, queue_size=Q)
        self.pub_score = rospy.Publisher("/sim/score", Score, queue_size=Q, latch=True)
        self.pub_rtf = rospy.Publisher("/sim/rtf", Float32, queue_size=Q, latch=True)
        self.pub_robots = rospy.Publisher("/sim/robots", PoseArray, queue_size=Q)
        self.pub_markers = rospy.Publisher("/sim/markers", MarkerArray, queue_size=Q, latch=True)
        self.pub_water = rospy.Publisher("/sim/water", WaterAccount, queue_size=Q, latch=True)
        rospy.set_param("/sim/robot_ids", [int(i) for i in sorted(self.sim.robots)])
        self.io = {rid: RobotIO(self, r, k) for k, (rid, r) in enumerate(sorted(self.sim.robots.items()))}
        self.fault_srv = rospy.Service("/sim/inject_fault", InjectFault, self.on_fault)
        self.due_fires = Due(C.FIRES_RATE)
        self.due_markers = Due(C.MARKER_RATE)
        stamp = rospy.Time(0)
        self.pub_tf_static.publish(TFMessage([t for io in self.io.values() for t in io.static_tfs(stamp)]))
        rospy.loginfo(f"[ual_sim] world '{world.name}' seed {prm['seed']}: {len(world.bmin)} boxes, robots "
                      f"{sorted(self.sim.robots)}, active fires "
                      f"{[f.holder.id for f in self.sim.fires.active()]}, rtf {prm['rtf']}")

    # ------------------------------------------------------------------ helpers
    @staticmethod
    def _denied_indoors_override(value) -> Optional[bool]:
        """~gnss_denied_indoors: "" = as the uncertainty profile says, else true / false."""
        if value in ("", None):
            return None
        if isinstance(value, bool):
            return value
        text = str(value).strip().lower()
        if text in ("true", "false"):
            return text == "true"
        rospy.logerr(f"[ual_sim] ~gnss_denied_indoors must be true, false or empty, got {value!r}; "
                     "using the uncertainty profile's")
        return None

    def _log_unknowns(self, name: str) -> None:
        """One line of what this trial drew (for the referee's reader; no robot reads the log)."""
        u = self.sim.uncertainty
        if u is None:
            rospy.loginfo(f"[ual_sim] uncertainty '{name}': none (GNSS indoors)")
            return
        k = u.unknowns
        fires = {f.holder.id: round(f.litres_needed, 2) for f in self.sim.fires.active()}
        rospy.loginfo(f"[ual_sim] uncertainty '{name}': litres needed {fires}, jet spot x{k.jet_spot_factor:.2f} "
                      f"drop {k.jet_drop_per_m2:.3f} m/m^2, sun-heated walls "
                      f"{'file' if k.box_temp is None else f'{k.box_temp.min():.1f}-{k.box_temp.max():.1f} degC'}, "
                      f"GNSS bias {({rid: np.round(u.gnss_bias(rid), 2).tolist() for rid in sorted(u.gnss)})}, "
                      f"GNSS {'denied' if u.cfg.gnss.denied_indoors else 'available'} indoors")

    @staticmethod
    def _stop_listening_to_own_clock() -> bool:
        """With /use_sim_time rospy subscribes this node to /clock, i.e. to itself: hundreds of messages a
        second to deserialize for nothing. Drop that subscription and set rospy's time directly instead
        (private rospy API; if it is not there, the subscription simply stays)."""
        try:
            from rospy.impl import simtime
            from rospy import rostime
            sub = getattr(simtime, "_clock_sub", None)
            if sub is None or not hasattr(rostime, "_set_rostime"):
                return False
            sub.unregister()
            simtime._clock_sub = None
            return True
        except Exception as e:  # noqa: BLE001 - any failure only costs performance
            rospy.logwarn(f"[ual_sim] keeping the /clock self-subscription: {e}")
            return False

    def timed(self, name: str, fn: Callable[[], None]) -> None:
        """Run fn and account its CPU time per sensor frame (reported in the log and by the benchmark)."""
        t0 = time.thread_time()
        fn()
        acc = self.cpu.setdefault(name, [0.0, 0])
        acc[0] += time.thread_time() - t0
        acc[1] += 1

    def wait_for(self, r: Robot) -> None:
        """Block a service thread until the robot's command is done, it crashed, or the node shuts down."""
        while not rospy.is_shutdown():
            with self.sim.lock:
                if r.goal_reached() or r.crashed:
                    return
            time.sleep(0.005)

    def on_fault(self, req) -> InjectFaultResponse:
        with self.sim.lock:
            ok, msg = self.sim.inject_fault(int(req.robot_id), req.kind, float(req.duration))
        if not ok:
            rospy.logerr(f"[ual_sim] inject_fault: {msg}")
        return InjectFaultResponse(ok, msg)

    # ------------------------------------------------------------------ main loop
    def spin(self) -> None:
        prm = self.params
        dt = 1.0 / prm["sim_rate"]
        rtf = prm["rtf"]
        wall0 = time.monotonic()
        sim_t0 = self.sim.time
        last_report_wall, last_report_sim, last_log_wall = wall0, sim_t0, wall0
        # /clock: one per tick, or at most ~clock_rate a wall second. Every node wakes on each one (16 in a
        # trial): at 8x real time, one per tick (240 a wall second) is a third of all messages of the graph.
        # Off by default: with 100, two trials under a load average of 60-70 failed (5/8 and 6/8 fires out;
        # agents declared silent, a starved central unit) where the code before did not, and there was no
        # time to tell whether the coarser ROS time was the cause
        clock_due = AtMostPerWallSecond(prm["clock_rate"])
        self.pub_clock.publish(Clock(rospy.Time(0)))
        while not rospy.is_shutdown():
            with self.sim.lock:
                for io in self.io.values():
                    io.apply_velocity()
                self.sim.step(dt)
                now = self.sim.time
                stamp = rospy.Time.from_sec(now)
                if clock_due():
                    self.pub_clock.publish(Clock(stamp))
                if self.own_clock:
                    rospy.rostime._set_rostime(stamp)
                tfs = [tf for io in self.io.values() if (tf := io.publish(now, stamp)) is not None]
                if tfs and self.pub_tf.get_num_connections():
                    self.pub_tf.publish(TFMessage(tfs))
                if self.due_fires(now):
                    self.publish_ground_truth(stamp)
                if prm["markers"] and self.due_markers(now) and self.pub_markers.get_num_connections():
                    self.publish_markers(stamp)
                for ev in self.sim.pop_events():
                    rospy.loginfo(f"[ual_sim] t={ev.time:.1f}s {ev.text}")
            wall = time.monotonic()
            if wall - last_report_wall >= 1.0:
                achieved = (now - last_report_sim) / (wall - last_report_wall)
                self.pub_rtf.publish(Float32(achieved))
                if wall - last_log_wall >= 10.0:   # every 10 s of wall time, whatever the factor
                    rospy.loginfo(f"[ual_sim] real-time factor {achieved:.2f} (target {rtf:g}); "
                                  + self.cpu_report())
                    last_log_wall = wall
                last_report_wall, last_report_sim = wall, now
            if rtf > 0:
                ahead = (now - sim_t0) / rtf - (wall - wall0)
                if ahead > 0:
                    time.sleep(ahead)
                else:                # behind: catch up at most ~catch_up_limit, never in a long burst
                    wall0 = paced_origin(wall0, ahead, prm["catch_up_limit"])

    def cpu_report(self) -> str:
        return ", ".join(f"{k} {1e3 * v[0] / max(v[1], 1):.2f} ms/frame" for k, v in sorted(self.cpu.items()))

    def publish_ground_truth(self, stamp: rospy.Time) -> None:
        sim = self.sim
        if self.pub_fires.get_num_connections():
            arr = FireStateArray(header=Header(stamp=stamp, frame_id=C.FRAME_ARENA))
            heat = sim.fires.heat()
            for i, f in enumerate(sim.fires.fires):
                h = f.holder
                temp = C.HEATER_TEMP * heat[i] if f.kind != 1 else (C.BLANKET_TEMP if f.covered else C.HEATER_TEMP)
                arr.fires.append(FireState(
                    id=h.id, kind=f.kind, floor=h.floor, active=f.active, extinguished=f.extinguished,
                    progress=f.progress, litres_received=f.litres, litres_needed=f.litres_needed,
                    temperature=temp if f.active else C.INACTIVE_HOLDER_TEMP,
                    position=Point(*h.position), normal=Vector3(*h.normal), extinguish_time=f.extinguish_time))
            self.pub_fires.publish(arr)
        sc = sim.score()
        self.pub_score.publish(Score(
            header=Header(stamp=stamp), score=sc["score"], max_score=sc["max_score"],
            fires_extinguished=len(sc["extinguished"]), elapsed=sc["elapsed"], time_left=sc["time_left"],
            extinguished_ids=[e[0] for e in sc["extinguished"]], extinguish_times=[e[1] for e in sc["extinguished"]],
            crashed_robots=[C.robot_ns(i) for i in sc["crashed"]]))
        if self.pub_water.get_num_connections():
            self.pub_water.publish(water_account(sim.water, Header(stamp=stamp)))
        if self.pub_robots.get_num_connections():
            self.pub_robots.publish(PoseArray(header=Header(stamp=stamp, frame_id=C.FRAME_ARENA), poses=[
                Pose(Point(*r.pos), yaw_quat(r.yaw)) for _, r in sorted(sim.robots.items())]))

    def publish_markers(self, stamp: rospy.Time) -> None:
        self.pub_markers.publish(build_markers(self.sim, stamp))


def main() -> None:
    rospy.init_node("ual_sim")
    node = SimNode()
    try:
        node.spin()
    except rospy.ROSInterruptException:
        pass
    rospy.loginfo(f"[ual_sim] shutting down at t={node.sim.time:.1f}s; {node.cpu_report()}")


__all__ = ["SimNode", "main"]
