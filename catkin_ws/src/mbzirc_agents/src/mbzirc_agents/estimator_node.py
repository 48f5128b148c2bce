"""ROS adapter of the object estimator: every robot's `sensed_objects` in, `estimated_objects` out.

Params (defaults): `~robot_ids` ([0, 1, 2, 3]: subscribes `/mbzirc2020_<id>/sensed_objects`),
`~min_updates` (5), `~lost_time` (10 s), `~fire_gate` (5.0 m), `~hole_gate` (0.4 m) (Euclidean caps),
`~chi2_gate` (16.27: Mahalanobis gate, 99.9 % for 3 dof), `~covariance_x/y/z` (1.5/1.5/0.5 m^2 variances,
used when a detection has no valid covariance), `~rate` (5 Hz),
`~publish_tentative` (false), `~global_frame` ('arena').
"""
from __future__ import annotations

import math
import threading

import numpy as np
import rospy
from mbzirc_comm_objs.msg import Object, ObjectDetectionList, ObjectList
from mbzirc_comm_objs.srv import SetObjectStatus, SetObjectStatusResponse

from . import constants as C
from .estimator_core import Detection, ObjectEstimator


class EstimatorNode:
    """Subscribes the detections, runs ObjectEstimator, publishes at a fixed rate."""

    def __init__(self) -> None:
        self.frame = rospy.get_param('~global_frame', C.GLOBAL_FRAME)
        cov = (rospy.get_param('~covariance_x', 1.5), rospy.get_param('~covariance_y', 1.5),
               rospy.get_param('~covariance_z', 0.5))
        self.core = ObjectEstimator(
            gates={C.TYPE_FIRE: float(rospy.get_param('~fire_gate', 5.0)),
                   C.TYPE_HOLE: float(rospy.get_param('~hole_gate', 0.4))},
            chi2_gate=float(rospy.get_param('~chi2_gate', 16.27)),
            min_updates=int(rospy.get_param('~min_updates', 5)),
            lost_time=float(rospy.get_param('~lost_time', 10.0)), default_covariance=cov)
        self.publish_tentative = bool(rospy.get_param('~publish_tentative', False))
        self.lock = threading.Lock()
        self.tf_buffer = None
        self.pub = rospy.Publisher('estimated_objects', ObjectList, queue_size=1)
        self.srv = rospy.Service('set_object_status', SetObjectStatus, self.on_set_status)
        self.subs = [rospy.Subscriber(f'/mbzirc2020_{int(i)}/sensed_objects', ObjectDetectionList,
                                      self.on_detections, queue_size=20)
                     for i in rospy.get_param('~robot_ids', [0, 1, 2, 3])]
        self.timer = rospy.Timer(rospy.Duration(1.0 / float(rospy.get_param('~rate', 5.0))), self.publish)

    def _to_global(self, det) -> np.ndarray:
        """Position of a detection in the global frame (tf2 when it is given in another frame)."""
        p = det.pose.pose.position
        frame = det.header.frame_id.lstrip('/')
        if frame in ('', self.frame):
            return np.array([p.x, p.y, p.z])
        if self.tf_buffer is None:
            import tf2_ros
            self.tf_buffer = tf2_ros.Buffer(rospy.Duration(10.0))
            self._tf_listener = tf2_ros.TransformListener(self.tf_buffer)
        import tf2_geometry_msgs  # noqa: F401  (registers PoseStamped transforms)
        from geometry_msgs.msg import PoseStamped
        ps = PoseStamped(header=det.header)
        ps.pose = det.pose.pose
        out = self.tf_buffer.transform(ps, self.frame, rospy.Duration(0.1))
        return np.array([out.pose.position.x, out.pose.position.y, out.pose.position.z])

    def on_detections(self, msg: ObjectDetectionList) -> None:
        """Fuse every detection of the list; a bad one is logged and skipped."""
        for det in msg.objects:
            try:
                pos = self._to_global(det)
                cov = np.array(det.pose.covariance, dtype=float).reshape(6, 6)[:3, :3] \
                    if len(det.pose.covariance) == 36 else np.zeros((3, 3))
                stamp = det.header.stamp.to_sec() or msg.stamp.to_sec() or rospy.get_time()
                d = Detection(type=det.type, position=pos, covariance=cov, stamp=stamp, agent_id=msg.agent_id,
                              camera_direction=det.image_detection.camera_direction,
                              scale=(det.scale.x, det.scale.y, det.scale.z))
                with self.lock:
                    self.core.add(d)
            except Exception as e:
                rospy.logerr_throttle(5.0, f'estimator: detection from {msg.agent_id!r} skipped: {e}')

    def on_set_status(self, req) -> SetObjectStatusResponse:
        """Set a track's status (the response is empty: errors are logged)."""
        with self.lock:
            err = self.core.set_status(req.object_id, req.object_status, req.object_type)
        if err:
            rospy.logerr_throttle(2.0, f'set_object_status: {err}')
        else:
            rospy.loginfo(f'object {req.object_id} -> {C.STATUS_NAMES[req.object_status]}')
        return SetObjectStatusResponse()

    def publish(self, _event=None) -> None:
        """Age the tracks and publish them."""
        now = rospy.Time.now()
        with self.lock:
            self.core.tick(now.to_sec())
            tracks = self.core.objects(self.publish_tentative)
            msg = ObjectList(stamp=now)
            for t in tracks:
                o = Object()
                o.header.stamp = rospy.Time.from_sec(max(t.last_update, 0.0))
                o.header.frame_id = self.frame
                o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = map(float, t.position)
                o.pose.pose.orientation.w = 1.0
                cov = np.zeros((6, 6))
                cov[:3, :3] = t.covariance
                o.pose.covariance = [float(v) if math.isfinite(v) else 0.0 for v in cov.flatten()]
                o.scale.x, o.scale.y, o.scale.z = t.scale
                o.type, o.sub_type, o.id, o.status = t.type, t.sub_type, t.id, t.status
                o.color = 6 if t.type == C.TYPE_FIRE else 0
                o.num_updates = min(t.num_updates, 65535)
                o.last_update = rospy.Time.from_sec(max(t.last_update, 0.0))
                msg.objects.append(o)
        self.pub.publish(msg)
