"""ROS adapter of the anchored indoor pose (see the package README for topics and params).

Runs in the robot's namespace: subscribes `ual/pose`, `ual/gnss_status`, `slam_out_pose`; publishes
`localization/pose`, `localization/source` and the TF arena -> `<ns>/map`.
"""
from __future__ import annotations

import math
import threading

import rospy
from geometry_msgs.msg import PoseStamped, Quaternion, TransformStamped
from sensor_msgs.msg import NavSatStatus
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from mbzirc_arena.messages import GLOBAL_FRAME
from mbzirc_ros_utils.periodic import PeriodicTimer

from .anchor import IndoorPose, Params

SOURCE_CHECK_PERIOD = 0.2    # s of ROS time: how often a silent SLAM pose is noticed
SOURCE_KEEPALIVE = 1.0       # s: localization/source is sent on change and at least this often
THROTTLE = 5.0               # s between repeated warnings


def yaw_of(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def quat(yaw: float) -> Quaternion:
    return Quaternion(0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw))


class IndoorPoseNode:
    def __init__(self) -> None:
        g = rospy.get_param
        defaults = Params()
        self.core = IndoorPose(Params(**{k: type(getattr(defaults, k))(g(f"~{k}", getattr(defaults, k)))
                                         for k in Params.__dataclass_fields__}))
        ns = rospy.get_namespace().strip("/")
        self.map_frame = str(g("~map_frame", f"{ns}/map" if ns else "map"))
        self.arena_frame = str(g("~arena_frame", GLOBAL_FRAME))
        self.tf_period = float(g("~tf_period", 1.0))    # s; 0 = no TF
        self.lock = threading.Lock()
        self.pub_pose = rospy.Publisher("localization/pose", PoseStamped, queue_size=5)
        self.pub_source = rospy.Publisher("localization/source", String, queue_size=1, latch=True)
        self.pub_tf = rospy.Publisher("/tf", TFMessage, queue_size=5) if self.tf_period > 0 else None
        self.sent = (None, -math.inf)        # last source and when it was sent
        self.tf_sent = -math.inf
        self.m_pose = PoseStamped()
        self.m_pose.header.frame_id = self.arena_frame
        self.subs = [rospy.Subscriber("ual/pose", PoseStamped, self.on_reported, queue_size=5),
                     rospy.Subscriber("ual/gnss_status", NavSatStatus, self.on_gnss, queue_size=5),
                     rospy.Subscriber("slam_out_pose", PoseStamped, self.on_slam, queue_size=5)]
        self.timer = PeriodicTimer(SOURCE_CHECK_PERIOD, self.on_timer, "indoor pose source")

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
        with self.lock:
            out = self.core.on_slam(msg.header.stamp.to_sec(), p.x, p.y, yaw_of(msg.pose.orientation))
            anchor = self.core.anchor
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
        self._send_source(source, now)

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
            elif "jumped" in e:
                rospy.logerr_throttle(THROTTLE, f"indoor_pose: {e}")
            else:
                rospy.loginfo(f"indoor_pose: {e}")

    def shutdown(self) -> None:
        self.timer.shutdown()
        for s in self.subs:
            s.unregister()


def main() -> None:
    rospy.init_node("indoor_pose")
    node = IndoorPoseNode()
    rospy.on_shutdown(node.shutdown)
    rospy.spin()
