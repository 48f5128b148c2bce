"""ROS adapter of the object estimator: every robot's `sensed_objects` in, `estimated_objects` out.

Params (defaults): `~robot_ids` ([0, 1, 2, 3]: subscribes `/mbzirc2020_<id>/sensed_objects`),
`~min_updates` (5), `~lost_time` (10 s), `~fire_gate` (5.0 m), `~hole_gate` (0.4 m) (Euclidean caps),
`~chi2_gate` (16.27: Mahalanobis gate, 99.9 % for 3 dof), `~covariance_x/y/z` (1.5/1.5/0.5 m^2 variances,
used when a detection has no valid covariance), `~rate` (5 Hz),
`~publish_tentative` (false), `~global_frame` ('arena'),
`~state_file` ('' = off): JSON file of the tracks, loaded at start and saved (atomically) when they
change, at most every `~save_period` (1.0 s, wall clock) and at once when a published id or status changes
(a confirmation, `set_object_status`), and on shutdown, so that a respawned estimator resumes with the same
tracks, ids and statuses (see estimator_store for the stale-file guards; `~clock_wait`, 10 s wall: how long
a start waits for /clock to judge the file's age).
"""
from __future__ import annotations

import json
import math
import os
import threading
import time

import numpy as np
import rospy
from mbzirc_comm_objs.msg import Object, ObjectDetectionList, ObjectList
from mbzirc_comm_objs.srv import SetObjectStatus, SetObjectStatusResponse
from mbzirc_ros_utils.periodic import PeriodicTimer

from mbzirc_arena import messages as C
from . import store
from .core import Detection, ObjectEstimator


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
            lost_time=float(rospy.get_param('~lost_time', 10.0)), default_covariance=cov,
            pose_std=float(rospy.get_param('~pose_std', 0.7)))
        self.publish_tentative = bool(rospy.get_param('~publish_tentative', False))
        self.lock = threading.Lock()
        self.state_file = str(rospy.get_param('~state_file', '') or '')
        self.save_period = float(rospy.get_param('~save_period', 1.0))
        self._save_lock = threading.Lock()
        self._saved_body: str = ''
        self._saved_sig: tuple = ()
        self._last_save_wall = -1e9
        # the mission's identity: roslaunch's run id, new for every master (file from another mission = stale)
        self.mission = str(rospy.get_param('/run_id', '') or '') if self.state_file else ''
        if self.state_file:               # before the subscribers: no new track may take a restored id
            self._resume()
            rospy.on_shutdown(lambda: self.save(force=True))
        self.tf_buffer = None
        self.pub = rospy.Publisher('estimated_objects', ObjectList, queue_size=1)
        self.srv = rospy.Service('set_object_status', SetObjectStatus, self.on_set_status)
        self.subs = [rospy.Subscriber(f'/mbzirc2020_{int(i)}/sensed_objects', ObjectDetectionList,
                                      self.on_detections, queue_size=20)
                     for i in rospy.get_param('~robot_ids', [0, 1, 2, 3])]
        # not rospy.Timer: its thread dies when /clock goes back (mbzirc_ros_utils.periodic)
        self.timer = PeriodicTimer(1.0 / float(rospy.get_param('~rate', 5.0)), self.publish, 'estimator publish')

    # ---- persistence ------------------------------------------------------------------------------
    def _now_for_load(self) -> float:
        """ROS time to judge the file's age by; waits (10 s wall at most) for the first /clock message."""
        deadline = time.monotonic() + float(rospy.get_param('~clock_wait', 10.0))
        while not rospy.is_shutdown() and rospy.get_time() == 0.0 and time.monotonic() < deadline:
            time.sleep(0.05)
        return rospy.get_time()

    def _resume(self) -> None:
        """Load the tracks of `~state_file` when it is ours and of this mission; else start empty."""
        now = self._now_for_load() if os.path.exists(self.state_file) else rospy.get_time()
        res = store.load(self.state_file, self.mission, now)
        if res.kind == store.MISSING:
            rospy.loginfo(f'estimator: {res.reason}: starting with no tracks')
            return
        if res.kind == store.STALE:
            rospy.logwarn(f'estimator: ignoring stale tracks: {res.reason}; starting with no tracks')
            return
        if res.kind == store.OK:
            try:
                self.core.load_state(res.state)
            except ValueError as e:
                res = store.Loaded(store.INVALID, reason=f'{self.state_file}: {e}')
        if res.kind == store.INVALID:
            rospy.logerr(f'estimator: cannot resume from {res.reason}; starting with no tracks '
                         '(the file will be overwritten)')
            return
        ids = ', '.join(f'{t.id}:{C.STATUS_NAMES[t.status]}' for t in self.core.tracks.values())
        rospy.loginfo(f'estimator: resumed {len(self.core.tracks)} tracks from {self.state_file} '
                      f'({res.reason}), next id {self.core.next_id}: {ids}')
        self._saved_body = json.dumps(self.core.to_state(include_tentative=self.publish_tentative), sort_keys=True)
        self._saved_sig = self._published_signature()

    def _published_signature(self) -> tuple:
        """(id, status) of every published track: when it changes the file is written at once (an id or
        an EXTINGUISHED the central unit has seen must survive a crash right after)."""
        return tuple((t.id, t.status) for t in self.core.objects(self.publish_tentative))

    def save(self, force: bool = False) -> None:
        """Write the tracks when they changed: at once if forced or a published id / status changed,
        else at most every `~save_period` s. A write error is logged; the node goes on."""
        if not self.state_file:
            return
        with self._save_lock:
            due = time.monotonic() - self._last_save_wall >= self.save_period
            with self.lock:
                sig = self._published_signature()
                if not (force or due or sig != self._saved_sig):
                    return                  # cheap exit at most publish ticks: nothing serialised
                state = self.core.to_state(include_tentative=self.publish_tentative)
            body = json.dumps(state, sort_keys=True)
            if body == self._saved_body:
                self._last_save_wall = time.monotonic()     # checked: look again in save_period
                return
            try:
                store.save(self.state_file, store.encode(state, self.mission, rospy.get_time()))
            except OSError as e:
                rospy.logerr_throttle(10.0, f'estimator: cannot save tracks to {self.state_file}: {e}')
                return
            self._saved_body, self._saved_sig, self._last_save_wall = body, sig, time.monotonic()

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
            self.save(force=True)
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
                o.color = C.COLOR_FIRE if t.type == C.TYPE_FIRE else C.COLOR_UNKNOWN
                o.num_updates = min(t.num_updates, 65535)
                o.last_update = rospy.Time.from_sec(max(t.last_update, 0.0))
                msg.objects.append(o)
        self.pub.publish(msg)
        self.save()
