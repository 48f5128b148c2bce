"""ROS adapter of the SLAM core: the ``hector_mapping`` node with the original node's interface.

Subscribes ``scan`` (``~scan_topic``), ``syscommand`` ("reset"), ``initialpose``; publishes ``map`` and
``map_metadata`` (latched), ``slam_out_pose``, ``poseupdate``, ``slam_cloud``, ``scanmatch_odom`` (when
``~pub_odometry``); serves ``dynamic_map``, ``reset_map``, ``pause_mapping``; publishes TF map -> odom
and map -> ``~tf_map_scanmatch_transform_frame_name``. All names are relative, so the node runs in a
robot's namespace.
"""
from __future__ import annotations

import math
import threading
from typing import Optional

import numpy as np
import rospy
import tf2_ros
from mbzirc_ros_utils.periodic import PeriodicTimer
from geometry_msgs.msg import (Point32, PoseStamped, PoseWithCovarianceStamped, TransformStamped)
from nav_msgs.msg import MapMetaData, OccupancyGrid, Odometry
from nav_msgs.srv import GetMap, GetMapRequest, GetMapResponse
from rospy.numpy_msg import numpy_msg
from sensor_msgs.msg import LaserScan, PointCloud
from std_msgs.msg import String
from std_srvs.srv import SetBool, SetBoolResponse, Trigger, TriggerResponse

from .constants import NODE_PARAM_DEFAULTS
from .geometry import compose, inverse, quaternion_from_yaw, rotation_matrix, wrap_angle, yaw_from_quaternion
from .scan import ScanFilter, check_scan, enough_points, laser_to_base, scan_to_points
from .slam import HectorSlam, SlamParams

#: How long a scan callback waits for a transform (s): short, so a missing frame never stalls the queue.
TF_TIMEOUT = 0.1
YAW_PRIOR_MAX_GAP = 1.0     # s between two scans beyond which the yaw prior is not used (a pause, a jump)
#: Seconds between repeats of the same warning.
THROTTLE = 5.0


class _Int8Data(np.ndarray):
    """int8 array that serialises through rospy's numpy_msg without numpy's deprecated tostring()."""

    def tostring(self) -> bytes:  # noqa: D401 - the name genpy calls
        """Raw bytes of the array."""
        return self.tobytes()


class _NumpyGetMap:
    """nav_msgs/GetMap whose response serialises its map data as a numpy array (a 2048 x 2048 map in
    milliseconds instead of seconds)."""

    _type = GetMap._type
    _md5sum = GetMap._md5sum
    _request_class = GetMapRequest
    _response_class = numpy_msg(GetMapResponse)


def _params() -> dict:
    """The node's ``~`` parameters with the original defaults."""
    return {name: rospy.get_param("~" + name, default) for name, default in NODE_PARAM_DEFAULTS.items()}


def _pose2d_from_msg(pose) -> np.ndarray:
    """geometry_msgs/Pose -> (x, y, yaw)."""
    q = pose.orientation
    return np.array([pose.position.x, pose.position.y, yaw_from_quaternion(q.x, q.y, q.z, q.w)])


def _fill_pose(msg_pose, pose: np.ndarray) -> None:
    """(x, y, yaw) -> geometry_msgs/Pose (in place)."""
    msg_pose.position.x, msg_pose.position.y, msg_pose.position.z = float(pose[0]), float(pose[1]), 0.0
    q = quaternion_from_yaw(float(pose[2]))
    msg_pose.orientation.x, msg_pose.orientation.y, msg_pose.orientation.z, msg_pose.orientation.w = q


def _covariance6(cov3: np.ndarray) -> list[float]:
    """3x3 (x, y, yaw) covariance -> row-major 6x6 (x, y, z, roll, pitch, yaw), unobserved axes large."""
    c = np.zeros((6, 6))
    ix = [0, 1, 5]
    c[np.ix_(ix, ix)] = cov3
    c[2, 2] = c[3, 3] = c[4, 4] = 1e6
    return c.reshape(-1).tolist()


class HectorMappingNode:
    """The hector_mapping node: reads ``~`` params, wires topics/services/TF to a :class:`HectorSlam`."""

    def __init__(self) -> None:
        p = _params()
        self.p = p
        self.slam = HectorSlam(SlamParams(
            map_resolution=float(p["map_resolution"]), map_size=int(p["map_size"]),
            map_start_x=float(p["map_start_x"]), map_start_y=float(p["map_start_y"]),
            map_multi_res_levels=int(p["map_multi_res_levels"]),
            update_factor_free=float(p["update_factor_free"]),
            update_factor_occupied=float(p["update_factor_occupied"]),
            map_update_distance_thresh=float(p["map_update_distance_thresh"]),
            map_update_angle_thresh=float(p["map_update_angle_thresh"])))
        self.filter = ScanFilter(float(p["laser_min_dist"]), float(p["laser_max_dist"]),
                                 float(p["laser_z_min_value"]), float(p["laser_z_max_value"]))
        self.base_frame = str(p["base_frame"])
        self.map_frame = str(p["map_frame"])
        self.odom_frame = str(p["odom_frame"])
        self.scanmatch_frame = str(p["tf_map_scanmatch_transform_frame_name"])
        self.lock = threading.Lock()
        self.paused = False
        self.scans_processed = 0
        self._start_pending = bool(p["use_tf_pose_start_estimate"])
        self.yaw_prior_frame = str(p["yaw_prior_frame"])
        self._prior_yaw: Optional[tuple[float, float]] = None     # (stamp, yaw) at the last scan processed
        self._prior_tf_comes = True          # the yaw prior's TF was there at the last scan
        self._last_map_stamp = rospy.Time(0)

        self.tf_buffer = tf2_ros.Buffer(rospy.Duration(30.0))
        self.tf_listener = tf2_ros.TransformListener(self.tf_buffer)
        self.tf_broadcaster = tf2_ros.TransformBroadcaster()

        self.map_pub = rospy.Publisher("map", numpy_msg(OccupancyGrid), queue_size=1, latch=True)
        self.meta_pub = rospy.Publisher("map_metadata", MapMetaData, queue_size=1, latch=True)
        self.pose_pub = rospy.Publisher("slam_out_pose", PoseStamped, queue_size=1)
        self.poseupdate_pub = rospy.Publisher("poseupdate", PoseWithCovarianceStamped, queue_size=1)
        self.cloud_pub = rospy.Publisher("slam_cloud", PointCloud, queue_size=1)
        self.odom_pub = (rospy.Publisher("scanmatch_odom", Odometry, queue_size=50)
                         if p["pub_odometry"] else None)

        if p["advertise_map_service"]:
            self.map_srv = rospy.Service("dynamic_map", _NumpyGetMap, self._on_get_map)
        self.reset_srv = rospy.Service("reset_map", Trigger, self._on_reset_map)
        self.pause_srv = rospy.Service("pause_mapping", SetBool, self._on_pause)
        rospy.Subscriber("syscommand", String, self._on_syscommand, queue_size=10)
        rospy.Subscriber("initialpose", PoseWithCovarianceStamped, self._on_initial_pose, queue_size=2)
        self.scan_sub = self._subscribe_scans()
        period = float(p["map_pub_period"])
        # not rospy.Timer: its thread dies when /clock goes back (mbzirc_ros_utils.periodic)
        self.map_timer = PeriodicTimer(max(period, 0.05), self._on_map_timer, 'hector map publication')

    def _subscribe_scans(self) -> rospy.Subscriber:
        return rospy.Subscriber(str(self.p["scan_topic"]), LaserScan, self._on_scan,
                                queue_size=int(self.p["scan_subscriber_queue_size"]), buff_size=1 << 20)

    # ---- scans ---------------------------------------------------------------------------------
    def _on_scan(self, msg: LaserScan) -> None:
        """Validate, transform, match, update, publish. Bad scans are skipped with a throttled warning."""
        if self.paused:
            return
        problem = check_scan(len(msg.ranges), msg.angle_min, msg.angle_max, msg.angle_increment)
        if problem:
            rospy.logwarn_throttle(THROTTLE, f"hector_mapping: skipping scan: {problem}")
            return
        pts = scan_to_points(np.asarray(msg.ranges, np.float64), msg.angle_min, msg.angle_increment,
                             msg.range_min, msg.range_max, self.filter)
        mount = self._laser_mount(msg)
        if mount is None:
            return
        pts, origin = laser_to_base(pts, mount[0], mount[1], self.filter)
        if not enough_points(pts):
            rospy.logwarn_throttle(THROTTLE, f"hector_mapping: skipping scan with {len(pts)} usable points "
                                   f"(NaN, inf or outside [{self.filter.laser_min_dist}, "
                                   f"{self.filter.laser_max_dist}] m)")
            return
        stamp = msg.header.stamp
        prior = self._prior_yaw_at(stamp)
        with self.lock:
            if self._start_pending:
                start = self._lookup_pose(self.map_frame, self.base_frame, stamp)
                if start is None:
                    rospy.logwarn_throttle(THROTTLE, "hector_mapping: use_tf_pose_start_estimate: no TF "
                                           f"{self.map_frame} -> {self.base_frame}; waiting")
                    return
                self.slam.reset(start)
                self._start_pending = False
            try:
                step = self.slam.process(pts, origin, stamp.to_sec(), self._yaw_change(prior))
            except ValueError as e:
                rospy.logwarn_throttle(THROTTLE, f"hector_mapping: skipping scan: {e}")
                return
            self._prior_yaw = prior
            self.scans_processed += 1
        self._publish_pose(step.pose, step.covariance, stamp)
        if self.cloud_pub.get_num_connections() > 0:
            cloud = PointCloud()
            cloud.header.stamp = stamp
            cloud.header.frame_id = self.base_frame
            cloud.points = [Point32(float(x), float(y), 0.0) for x, y in pts]
            self.cloud_pub.publish(cloud)

    def _prior_yaw_at(self, stamp: rospy.Time) -> Optional[tuple[float, float]]:
        """(stamp, yaw) of base_frame in ~yaw_prior_frame at the scan's own stamp; None when off or there is
        no TF then. Not the latest TF: under load a scan is processed late, and the turn between the times
        two scans were processed is not the turn between the scans."""
        if not self.yaw_prior_frame:
            return None
        # waits for the TF of the scan's stamp (it comes a moment after the scan) only while the frames are
        # connected: a frame that is not there must not hold every scan up by the timeout (hector would fall
        # behind its laser); a TF only late does not stop the waiting
        wait = TF_TIMEOUT if self._prior_tf_comes else 0.0
        try:
            tf = self.tf_buffer.lookup_transform(self.yaw_prior_frame, self.base_frame, stamp, rospy.Duration(wait))
        except tf2_ros.TransformException as e:
            self._prior_tf_comes = isinstance(e, tf2_ros.ExtrapolationException)
            rospy.logwarn_throttle(THROTTLE, f"hector_mapping: no yaw prior for this scan: no TF "
                                   f"{self.yaw_prior_frame} -> {self.base_frame} at its stamp: {e}")
            return None
        self._prior_tf_comes = True
        q = tf.transform.rotation
        return stamp.to_sec(), yaw_from_quaternion(q.x, q.y, q.z, q.w)

    def _yaw_change(self, prior: Optional[tuple[float, float]]) -> Optional[float]:
        """The turn since the last scan processed by the yaw prior (None: no prior for either scan, or more
        than YAW_PRIOR_MAX_GAP s between them)."""
        last = self._prior_yaw
        if prior is None or last is None or not 0.0 <= prior[0] - last[0] <= YAW_PRIOR_MAX_GAP:
            return None
        return wrap_angle(prior[1] - last[1])

    def _laser_mount(self, msg: LaserScan) -> Optional[tuple[np.ndarray, np.ndarray]]:
        """Rotation and translation of the laser frame in the base frame (identity without TF use)."""
        frame = msg.header.frame_id
        if not self.p["use_tf_scan_transformation"] or frame == self.base_frame:
            return np.eye(3), np.zeros(3)
        if not frame:
            rospy.logwarn_throttle(THROTTLE, "hector_mapping: skipping scan with an empty frame_id")
            return None
        try:
            tf = self.tf_buffer.lookup_transform(self.base_frame, frame, rospy.Time(0),
                                                 rospy.Duration(TF_TIMEOUT))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException,
                tf2_ros.InvalidArgumentException, tf2_ros.TransformException) as e:
            rospy.logwarn_throttle(THROTTLE, f"hector_mapping: skipping scan: no TF {self.base_frame} <- "
                                   f"{frame}: {e}")
            return None
        q = tf.transform.rotation
        t = tf.transform.translation
        return rotation_matrix(q.x, q.y, q.z, q.w), np.array([t.x, t.y, t.z])

    def _lookup_pose(self, parent: str, child: str, stamp: rospy.Time) -> Optional[np.ndarray]:
        """(x, y, yaw) of ``child`` in ``parent`` at ``stamp`` (or the latest), None if unavailable."""
        for when in (stamp, rospy.Time(0)):
            try:
                tf = self.tf_buffer.lookup_transform(parent, child, when, rospy.Duration(TF_TIMEOUT))
            except tf2_ros.TransformException:
                continue
            t, q = tf.transform.translation, tf.transform.rotation
            return np.array([t.x, t.y, yaw_from_quaternion(q.x, q.y, q.z, q.w)])
        return None

    # ---- outputs -------------------------------------------------------------------------------
    def _publish_pose(self, pose: np.ndarray, cov3: np.ndarray, stamp: rospy.Time) -> None:
        """slam_out_pose, poseupdate, scanmatch_odom and the TFs for one estimate."""
        ps = PoseStamped()
        ps.header.stamp = stamp
        ps.header.frame_id = self.map_frame
        _fill_pose(ps.pose, pose)
        self.pose_pub.publish(ps)
        pc = PoseWithCovarianceStamped()
        pc.header = ps.header
        pc.pose.pose = ps.pose
        pc.pose.covariance = _covariance6(cov3)
        self.poseupdate_pub.publish(pc)
        if self.odom_pub is not None:
            od = Odometry()
            od.header = ps.header
            od.child_frame_id = self.base_frame
            od.pose = pc.pose
            self.odom_pub.publish(od)
        transforms = []
        if self.p["pub_map_scanmatch_transform"]:
            transforms.append(self._tf(self.map_frame, self.scanmatch_frame, pose, stamp))
        if self.p["pub_map_odom_transform"]:
            if self.odom_frame == self.base_frame:
                transforms.append(self._tf(self.map_frame, self.odom_frame, pose, stamp))
            else:
                odom_base = self._lookup_pose(self.odom_frame, self.base_frame, stamp)
                if odom_base is None:
                    rospy.logwarn_throttle(THROTTLE, f"hector_mapping: no TF {self.odom_frame} -> "
                                           f"{self.base_frame}; not publishing {self.map_frame} -> "
                                           f"{self.odom_frame}")
                else:
                    transforms.append(self._tf(self.map_frame, self.odom_frame,
                                               compose(pose, inverse(odom_base)), stamp))
        if transforms:
            self.tf_broadcaster.sendTransform(transforms)

    @staticmethod
    def _tf(parent: str, child: str, pose: np.ndarray, stamp: rospy.Time) -> TransformStamped:
        t = TransformStamped()
        t.header.stamp = stamp
        t.header.frame_id = parent
        t.child_frame_id = child
        t.transform.translation.x, t.transform.translation.y = float(pose[0]), float(pose[1])
        q = quaternion_from_yaw(float(pose[2]))
        r = t.transform.rotation
        r.x, r.y, r.z, r.w = q
        return t

    def build_map(self) -> OccupancyGrid:
        """The finest level as an OccupancyGrid in the map frame (numpy-backed data)."""
        with self.lock:
            level = self.slam.levels[0]
            box = level.known_bounds() if self.p["map_pub_known_area"] else None
            if box is None:                      # the original's whole grid
                box = (0, 0, level.size - 1, level.size - 1)
            data = level.occupancy_grid_data(box).reshape(-1).view(_Int8Data)
        msg = numpy_msg(OccupancyGrid)()
        msg.header.stamp = rospy.Time.now()
        msg.header.frame_id = self.map_frame
        info = msg.info
        info.map_load_time = msg.header.stamp
        info.resolution = level.resolution
        info.width, info.height = box[2] - box[0] + 1, box[3] - box[1] + 1
        info.origin.position.x = float(level.corner[0]) + box[0] * level.resolution
        info.origin.position.y = float(level.corner[1]) + box[1] * level.resolution
        info.origin.orientation.w = 1.0
        msg.data = data
        return msg

    def _on_map_timer(self, _event) -> None:
        """Publish map and map_metadata every ``~map_pub_period``."""
        if self.map_pub.get_num_connections() == 0 and self.meta_pub.get_num_connections() == 0 \
                and self._last_map_stamp != rospy.Time(0):
            return
        msg = self.build_map()
        self._last_map_stamp = msg.header.stamp
        self.map_pub.publish(msg)
        self.meta_pub.publish(msg.info)

    # ---- services and commands -----------------------------------------------------------------
    def _on_get_map(self, _req) -> GetMapResponse:
        resp = numpy_msg(GetMapResponse)()
        resp.map = self.build_map()
        return resp

    def reset(self, pose: Optional[np.ndarray] = None) -> None:
        """Clear the map and restart at ``pose`` (default the origin)."""
        with self.lock:
            self.slam.reset(pose)
            self._prior_yaw = None
        rospy.loginfo("hector_mapping: map reset")

    def _on_reset_map(self, _req) -> TriggerResponse:
        self.reset()
        return TriggerResponse(success=True, message="map and pose reset")

    def _on_pause(self, req) -> SetBoolResponse:
        """Paused, the node also leaves its scan and TF subscriptions: a robot's mapping paused away from the
        buildings (indoor_localization's mapping gate) then costs nothing, where reading every robot's TF
        at the simulator's rate was most of what a paused node spent. Resumed, it subscribes again; the
        buffer keeps the static transforms (the laser's mount)."""
        paused = bool(req.data)
        with self.lock:
            changed, self.paused = paused != self.paused, paused
            if changed and paused:
                self.scan_sub.unregister()
                self.tf_listener.unregister()
            elif changed:
                self.tf_listener = tf2_ros.TransformListener(self.tf_buffer)
                self.scan_sub = self._subscribe_scans()
                self._prior_yaw = None
        state = "paused" if paused else "resumed"
        rospy.loginfo(f"hector_mapping: mapping {state}")
        return SetBoolResponse(success=True, message=f"mapping {state}")

    def _on_syscommand(self, msg: String) -> None:
        if msg.data == "reset":
            self.reset()

    def _on_initial_pose(self, msg: PoseWithCovarianceStamped) -> None:
        """The next scan is matched from this pose (map frame); the map is kept, as the original's (its
        `reset_map` / syscommand `reset` clear it). A way to put a lost matcher back on the map."""
        pose = _pose2d_from_msg(msg.pose.pose)
        if not np.all(np.isfinite(pose)):
            rospy.logerr_throttle(THROTTLE, "hector_mapping: ignoring initialpose with NaN/inf")
            return
        with self.lock:
            self.slam.set_pose(pose)
            self._prior_yaw = None
        rospy.loginfo(f"hector_mapping: next match from initialpose ({pose[0]:.2f}, {pose[1]:.2f}, "
                      f"{math.degrees(pose[2]):.1f} deg), map kept")


def main() -> None:
    """Entry point of scripts/hector_mapping."""
    rospy.init_node("hector_mapping")
    HectorMappingNode()
    rospy.spin()
