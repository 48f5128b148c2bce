"""ROS adapter of the anchored indoor pose (see the package README for topics and params).

Runs in the robot's namespace: subscribes `ual/pose`, `ual/gnss_status`, `slam_out_pose` and (for the
refinement by the building's outline) `scan`; publishes `localization/pose`, `localization/source` and the TF
arena -> `<ns>/map`; pauses and resumes hector_mapping (its `pause_mapping` and `reset_map` services) by the
distance to the buildings (mapping_gate.py).
"""
from __future__ import annotations

import math
import threading

import rospy
from rospy.numpy_msg import numpy_msg
from geometry_msgs.msg import PoseStamped, Quaternion, TransformStamped
from sensor_msgs.msg import LaserScan, NavSatStatus
from std_msgs.msg import String
from std_srvs.srv import SetBool, Trigger
from tf2_msgs.msg import TFMessage

from mbzirc_arena.arena import load_arena
from mbzirc_arena.c3 import ARENA
from mbzirc_arena.messages import GLOBAL_FRAME
from mbzirc_ros_utils.periodic import PeriodicTimer

from .anchor import IndoorPose, Params
from .mapping_gate import MappingGate
from .outline import RefineParams
from .refinement import OutlineRefinement

SOURCE_CHECK_PERIOD = 0.2    # s of ROS time: how often a silent SLAM pose is noticed
SOURCE_KEEPALIVE = 1.0       # s: localization/source is sent on change and at least this often
THROTTLE = 5.0               # s between repeated warnings


def yaw_of(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def quat(yaw: float) -> Quaternion:
    return Quaternion(0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


def params_from_ros(cls, prefix: str):
    """A params dataclass with every field read from `~<prefix><field>` (defaults: the dataclass's)."""
    defaults = cls()
    return cls(**{k: type(getattr(defaults, k))(rospy.get_param(f"~{prefix}{k}", getattr(defaults, k)))
                  for k in cls.__dataclass_fields__})


def outline_refinement_from_ros(arena) -> OutlineRefinement:
    """The node's OutlineRefinement, its params read from `~` (README, "Params")."""
    g = rospy.get_param
    return OutlineRefinement(
        arena, params_from_ros(RefineParams, "outline/"), correction_rate=float(g("~correction_rate", 1.0)),
        yaw_correction_rate=float(g("~yaw_correction_rate", 0.1)), scan_period=float(g("~scan_period", 0.2)),
        crossing_at_once=float(g("~crossing_at_once", 1.0)),
        outdoor_memory=float(g("~outdoor_memory", 10.0)),
        laser_offset=(float(g("~laser_offset_x", 0.0)), float(g("~laser_offset_y", 0.0))),
        info=rospy.loginfo, warn=lambda m: rospy.logwarn_throttle(THROTTLE, m))


class IndoorPoseNode:
    def __init__(self) -> None:
        g = rospy.get_param
        world = str(g("~world_file", ""))
        arena = load_arena(world) if world else ARENA      # its public outline only
        self.core = IndoorPose(params_from_ros(Params, ""), arena.footprints)
        self.outline = outline_refinement_from_ros(arena) if bool(g("~outline_refinement", True)) else None
        resume, pause = float(g("~resume_mapping_within", 8.0)), float(g("~pause_mapping_beyond", 10.0))
        if 0 < pause < resume:
            rospy.logerr(f"indoor_pose: ~resume_mapping_within {resume} m is beyond ~pause_mapping_beyond {pause} m: "
                         f"resuming within {pause} m")
            resume = pause
        self.gate = MappingGate(arena.footprints, resume, pause)
        self.mapping_applied = True          # hector_mapping matches from its start
        self.pause_mapping = rospy.ServiceProxy(str(g("~pause_mapping_service", "pause_mapping")), SetBool)
        self.reset_map = rospy.ServiceProxy(str(g("~reset_map_service", "reset_map")), Trigger)
        ns = rospy.get_namespace().strip("/")
        self.map_frame = str(g("~map_frame", f"{ns}/map" if ns else "map"))
        self.arena_frame = str(g("~arena_frame", GLOBAL_FRAME))
        self.tf_period = float(g("~tf_period", 1.0))    # s; 0 = no TF
        self.lock = threading.Lock()
        self.pub_pose = rospy.Publisher("localization/pose", PoseStamped, queue_size=5)
        self.pub_source = rospy.Publisher("localization/source", String, queue_size=1, latch=True)
        self.pub_tf = rospy.Publisher("/tf", TFMessage, queue_size=5) if self.tf_period > 0 else None
        # hector_mapping's command topic: "reset" starts a new map (re-localization after a jump, anchor.py)
        self.pub_slam_command = rospy.Publisher(str(g("~slam_command_topic", "syscommand")), String, queue_size=1)
        self.sent = (None, -math.inf)        # last source and when it was sent
        self.tf_sent = -math.inf
        self.m_pose = PoseStamped()
        self.m_pose.header.frame_id = self.arena_frame
        self.subs = [rospy.Subscriber("ual/pose", PoseStamped, self.on_reported, queue_size=5),
                     rospy.Subscriber("ual/gnss_status", NavSatStatus, self.on_gnss, queue_size=5),
                     rospy.Subscriber("slam_out_pose", PoseStamped, self.on_slam, queue_size=5)]
        self.scan_sub = self._subscribe_scans()
        self.timer = PeriodicTimer(SOURCE_CHECK_PERIOD, self.on_timer, "indoor pose source")

    def _subscribe_scans(self):
        """The scans of the outline refinement (None without it); not while hector_mapping is paused: they
        are used only with its poses."""
        if self.outline is None:
            return None
        # numpy_msg: the ranges as an array, not a tuple of 720 floats (every scan is read, 1 in 3 used)
        return rospy.Subscriber("scan", numpy_msg(LaserScan), self.outline.on_scan, queue_size=2)

    # ---------------------------------------------------------------- callbacks
    def on_reported(self, msg: PoseStamped) -> None:
        p = msg.pose.position
        with self.lock:
            self.core.on_reported(msg.header.stamp.to_sec(), p.x, p.y, p.z, yaw_of(msg.pose.orientation))
        self._log()

    def on_gnss(self, msg: NavSatStatus) -> None:
        now = rospy.get_time()
        with self.lock:
            self.core.on_gnss(now, msg.status >= NavSatStatus.STATUS_FIX)
            source = self.core.source(now)
        self._log()
        self._send_source(source, now)

    def on_slam(self, msg: PoseStamped) -> None:
        if msg.header.frame_id.lstrip("/") != self.map_frame:
            rospy.logwarn_throttle(THROTTLE, f"indoor_pose: slam_out_pose in frame '{msg.header.frame_id}', "
                                             f"expected '{self.map_frame}'; ignored")
            return
        p = msg.pose.position
        t, yaw = msg.header.stamp.to_sec(), yaw_of(msg.pose.orientation)
        with self.lock:
            out = self.core.on_slam(t, p.x, p.y, yaw)
            if self.outline is not None and out is not None:
                self.outline.update(self.core, t, (p.x, p.y, yaw), out.z)
            anchor = self.core.refined_anchor()
            reset = self.core.take_reset_request()
        if reset:
            self.pub_slam_command.publish(String("reset"))
        self._log()
        if out is None:
            return
        m = self.m_pose
        m.header.stamp = msg.header.stamp
        m.pose.position.x, m.pose.position.y, m.pose.position.z = out.x, out.y, out.z
        m.pose.orientation = quat(out.yaw)
        self.pub_pose.publish(m)
        self._send_source(out.source, out.t)
        if self.pub_tf is not None and anchor is not None and out.t - self.tf_sent >= self.tf_period:
            self.tf_sent = out.t
            tf = TransformStamped()
            tf.header.stamp, tf.header.frame_id, tf.child_frame_id = msg.header.stamp, self.arena_frame, self.map_frame
            tf.transform.translation.x, tf.transform.translation.y = anchor.tx, anchor.ty
            tf.transform.rotation = quat(anchor.theta)
            self.pub_tf.publish(TFMessage([tf]))

    def on_timer(self, _event) -> None:
        now = rospy.get_time()
        with self.lock:
            source = self.core.source(now)
            last = self.core.reported.latest()       # (t, x, y, z, yaw)
            if last is not None:
                self.gate.update(self.core.gnss_valid, last[1], last[2])
        self._send_source(source, now)
        self._apply_mapping_gate()

    def _apply_mapping_gate(self) -> None:
        """Pause hector_mapping, or resume it on a new map, as the gate says (retried while its services are
        not there). The core expects the new map before the reset: no pose of the old one comes after it
        (hector_mapping is paused until the last call)."""
        with self.lock:
            want = self.gate.running
        if want == self.mapping_applied:
            return
        try:
            if want:
                with self.lock:
                    self.core.expect_new_map()
                self.reset_map()
            self.pause_mapping(not want)
        except (rospy.ServiceException, rospy.ROSException) as e:
            rospy.logwarn_throttle(THROTTLE, f"indoor_pose: could not {'resume' if want else 'pause'} "
                                             f"hector_mapping: {e}")
            return
        self.mapping_applied = want
        if want and self.scan_sub is None:
            self.scan_sub = self._subscribe_scans()
        elif not want and self.scan_sub is not None:
            self.scan_sub.unregister()
            self.scan_sub = None
        self._log()
        rospy.loginfo("indoor_pose: hector_mapping " + (
            f"resumed on a new map (within {self.gate.resume_within:.0f} m of a building or no fix)" if want
            else f"paused (on GNSS, more than {self.gate.pause_beyond:.0f} m from every building)"))

    # ---------------------------------------------------------------- helpers
    def _send_source(self, source: str, now: float) -> None:
        last, when = self.sent
        if source == last and when <= now < when + SOURCE_KEEPALIVE:
            return
        if source != last:
            log = rospy.logwarn if source == "none" else rospy.loginfo
            log(f"indoor_pose: source {last} -> {source}")
        self.sent = (source, now)
        self.pub_source.publish(String(source))

    def _log(self) -> None:
        with self.lock:
            events = self.core.pop_events()
        for e in events:
            if e.startswith("ignoring"):
                rospy.logwarn_throttle(THROTTLE, f"indoor_pose: {e}")
            elif "jumped" in e or e.startswith("no ") or "no pose until" in e:
                rospy.logerr_throttle(THROTTLE, f"indoor_pose: {e}")
            else:
                rospy.loginfo(f"indoor_pose: {e}")

    def shutdown(self) -> None:
        self.timer.shutdown()
        for proxy in (self.pause_mapping, self.reset_map):
            proxy.close()
        for s in self.subs + ([self.scan_sub] if self.scan_sub is not None else []):
            s.unregister()


def main() -> None:
    rospy.init_node("indoor_pose")
    node = IndoorPoseNode()
    rospy.on_shutdown(node.shutdown)
    rospy.spin()
