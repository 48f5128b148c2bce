"""ROS adapter of the circle detector: synchronised colour + depth in, TYPE_HOLE sensed_objects out."""
from __future__ import annotations

import math
import threading
from typing import List, Optional

import message_filters
import numpy as np
import rospy
from geometry_msgs.msg import PointStamped
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
from mbzirc_ros_utils.periodic import PeriodicTimer
from sensor_msgs.msg import CameraInfo, Image
from visualization_msgs.msg import Marker

from circle_detector import constants as C
from circle_detector.hole_choice import choose_hole
from circle_detector.hough import Circle, HoughParams, Intrinsics, depth_to_metres, detect_circles
from circle_detector.images import image_to_array, to_bgr

THROTTLE_S = 5.0
SYNC_QUEUE = 10
SYNC_SLOP_S = 0.05
LAZY_POLL_S = 0.25   # s between checks of the on-demand outputs' subscribers (lazy mode)


def read_params() -> HoughParams:
    """The `~` params of the original node (same names and defaults) plus `~downscale` and `~rectify`."""
    g = rospy.get_param
    return HoughParams(
        dp=float(g("~dp", C.DEFAULT_DP)),
        min_dist_between_circle_center=float(g("~min_dist_between_circle_center", C.DEFAULT_MIN_DIST_BETWEEN_CIRCLE_CENTER)),
        canny_edge_upper_threshold=float(g("~canny_edge_upper_threshold", C.DEFAULT_CANNY_EDGE_UPPER_THRESHOLD)),
        accumulator_threshold=float(g("~accumulator_threshold", C.DEFAULT_ACCUMULATOR_THRESHOLD)),
        min_radius=int(g("~min_radius", C.DEFAULT_MIN_RADIUS)),
        max_radius=int(g("~max_radius", C.DEFAULT_MAX_RADIUS)),
        min_radius_meters=float(g("~min_radius_meters", C.DEFAULT_MIN_RADIUS_METERS)),
        max_radius_meters=float(g("~max_radius_meters", C.DEFAULT_MAX_RADIUS_METERS)),
        max_depth_th=float(g("~max_depth_th", C.DEFAULT_MAX_DEPTH_TH)),
        use_gaussian_blur=bool(g("~use_gaussian_blur", C.DEFAULT_USE_GAUSSIAN_BLUR)),
        gaussian_blur_sigma=float(g("~gaussian_blur_sigma", C.DEFAULT_GAUSSIAN_BLUR_SIGMA)),
        gaussian_blur_kernel_size=int(g("~gaussian_blur_kernel_size", C.DEFAULT_GAUSSIAN_BLUR_KERNEL_SIZE)),
        downscale=int(g("~downscale", C.DEFAULT_DOWNSCALE)),
        rectify=bool(g("~rectify", C.DEFAULT_RECTIFY)),
    )


class CircleDetectorNode:
    """Detects circles in each synchronised colour/depth pair of the robot's RealSense.

    .. note:: the original dropped images whose frame_id was not `<tf_prefix>/camera_color_optical_frame`;
       this port warns (throttled) and goes on, stamping detections with the image's own frame.
    """

    def __init__(self) -> None:
        self.tf_prefix = str(rospy.get_param("~tf_prefix", C.DEFAULT_TF_PREFIX))
        self.agent_id = self.tf_prefix.rsplit("_", 1)[-1]
        self.publish_debug_marker = bool(rospy.get_param("~publish_debug_marker", False))
        self.publish_debug_images = bool(rospy.get_param("~publish_debug_images", False))
        self.simulation = bool(rospy.get_param("~simulation", False))  # kept for compatibility, no effect
        self.select_middle_hole = bool(rospy.get_param("~select_middle_hole", False))
        self.params = read_params()
        self.expected_frame = f"{self.tf_prefix}/camera_color_optical_frame"
        self.K: Optional[Intrinsics] = None
        self.lock = threading.Lock()

        self.pub = rospy.Publisher("sensed_objects", ObjectDetectionList, queue_size=1)
        self.hole_pub = rospy.Publisher("circle_detection/middle_hole", PointStamped, queue_size=1)
        self.marker_pub = rospy.Publisher("circle_detection/circle_center_marker", Marker, queue_size=1) \
            if self.publish_debug_marker else None
        self.image_pub = rospy.Publisher("circle_detection/detected_circles_image", Image, queue_size=1) \
            if self.publish_debug_images else None
        self.lazy = bool(rospy.get_param("~lazy", False))
        self.camera_subs: list = []
        self.demand_timer = None
        if self.lazy:
            # like image_proc's lazy nodelets: camera images only while someone listens to an on-demand output
            # not rospy.Timer: its thread dies when /clock goes back (mbzirc_ros_utils.periodic)
            self.demand_timer = PeriodicTimer(LAZY_POLL_S, self.check_demand, 'circle detector demand')
        else:
            self.subscribe_camera()
        rospy.loginfo("circle_detector: radius %.2f-%.2f m, depth < %.1f m, downscale %d, rectify %s, lazy %s",
                      self.params.min_radius_meters, self.params.max_radius_meters, self.params.max_depth_th,
                      self.params.downscale, self.params.rectify, self.lazy)

    def demand(self) -> int:
        """Subscribers of the on-demand outputs (middle hole, debug marker and image).

        `sensed_objects` does not count: the object estimator listens to it all the time. A client that
        needs holes (the agent centring a facade hole) subscribes to `circle_detection/middle_hole`.
        """
        pubs = [self.hole_pub, self.marker_pub, self.image_pub]
        return sum(p.get_num_connections() for p in pubs if p is not None)

    def check_demand(self, _event=None) -> None:
        """Lazy mode: subscribe to the camera while there is demand, unsubscribe when there is none."""
        wanted = self.demand() > 0
        if wanted and not self.camera_subs:
            rospy.loginfo("circle_detector: a client needs holes, subscribing to the camera")
            self.subscribe_camera()
        elif not wanted and self.camera_subs:
            rospy.loginfo("circle_detector: no client needs holes, unsubscribing from the camera")
            self.unsubscribe_camera()

    def subscribe_camera(self) -> None:
        """Camera info, and colour + depth through an approximate-time synchroniser."""
        info = rospy.Subscriber("camera/color/camera_info", CameraInfo, self.on_camera_info, queue_size=1)
        color = message_filters.Subscriber("camera/color/image_rect_color", Image, queue_size=1)
        depth = message_filters.Subscriber("camera/aligned_depth_to_color/image_raw", Image, queue_size=1)
        self.sync = message_filters.ApproximateTimeSynchronizer([color, depth], SYNC_QUEUE, SYNC_SLOP_S)
        self.sync.registerCallback(self.on_images)
        self.camera_subs = [info, color, depth]

    def unsubscribe_camera(self) -> None:
        """Drop the camera subscriptions (the simulator stops rendering images nobody receives)."""
        for sub in self.camera_subs:
            sub.unregister()
        self.camera_subs = []

    def on_camera_info(self, msg: CameraInfo) -> None:
        try:
            K = Intrinsics.from_k(list(msg.K), msg.width, msg.height)
        except ValueError as err:
            rospy.logerr_throttle(THROTTLE_S, f"circle_detector: bad camera_info: {err}")
            return
        with self.lock:
            self.K = K

    def on_images(self, color: Image, depth: Image) -> None:
        with self.lock:
            K = self.K
        if K is None:
            rospy.logerr_throttle(THROTTLE_S, "circle_detector: no camera_info yet, images dropped")
            return
        if color.header.frame_id != self.expected_frame:
            rospy.logwarn_throttle(THROTTLE_S * 6, f"circle_detector: image frame {color.header.frame_id!r} "
                                   f"is not {self.expected_frame!r} (processing anyway)")
        try:
            bgr = to_bgr(image_to_array(color.height, color.width, color.encoding, color.step,
                                        color.is_bigendian, color.data), color.encoding)
            d = image_to_array(depth.height, depth.width, depth.encoding, depth.step, depth.is_bigendian, depth.data)
            depth_m = depth_to_metres(d, depth.encoding)
            if (color.width, color.height) != (K.width, K.height) and K.width > 0:
                raise ValueError(f"image {color.width}x{color.height} does not match camera_info {K.width}x{K.height}")
            circles = detect_circles(bgr, depth_m, K, self.params)
        except ValueError as err:
            rospy.logerr_throttle(THROTTLE_S, f"circle_detector: bad images: {err}")
            return
        try:
            self.publish(color, circles, bgr)
        except rospy.ROSException:  # publishers closed while shutting down
            if not rospy.is_shutdown():
                raise

    def publish(self, color: Image, circles: List[Circle], bgr: np.ndarray) -> None:
        stamp, frame = color.header.stamp, color.header.frame_id
        middle = choose_hole([(c.x, c.y, c.z, c.radius_m) for c in circles], [c.opening_m for c in circles])
        chosen = circles if not self.select_middle_hole else ([circles[middle]] if middle is not None else [])
        out = ObjectDetectionList(agent_id=self.agent_id, stamp=stamp)
        for c in chosen:
            det = ObjectDetection()
            det.header.stamp, det.header.frame_id = stamp, frame
            det.type, det.color = ObjectDetection.TYPE_HOLE, ObjectDetection.COLOR_UNKNOWN
            det.pose.pose.position.x, det.pose.pose.position.y, det.pose.pose.position.z = c.x, c.y, c.z
            det.pose.pose.orientation.w = 1.0
            det.relative_position.x, det.relative_position.y, det.relative_position.z = c.x, c.y, c.z
            det.scale.x = det.scale.y = det.scale.z = c.radius_m
            if math.isfinite(c.opening_m):
                # extension: the point seen through the middle of the circle (same ray, opening_m
                # further along the optical axis); all zeros when the depth had no data there
                k = (c.z + c.opening_m) / c.z
                det.point_of_interest.x, det.point_of_interest.y, det.point_of_interest.z = \
                    c.x * k, c.y * k, c.z * k
            out.objects.append(det)
        self.pub.publish(out)
        if middle is not None:
            m = circles[middle]
            p = PointStamped()
            p.header.stamp, p.header.frame_id = stamp, frame
            p.point.x, p.point.y, p.point.z = m.x, m.y, m.z
            self.hole_pub.publish(p)
        if self.marker_pub is not None:
            for i, c in enumerate(circles):
                mk = Marker(type=Marker.SPHERE, action=Marker.ADD, ns="circle_center", id=i)
                mk.header.stamp, mk.header.frame_id = stamp, frame
                mk.pose.position.x, mk.pose.position.y, mk.pose.position.z = c.x, c.y, c.z
                mk.pose.orientation.w = 1.0
                mk.scale.x = mk.scale.y = mk.scale.z = 2 * c.radius_m
                mk.color.a, mk.color.r, mk.color.g = 1.0, 1.0, 1.0 if i == middle else 0.0
                mk.lifetime = rospy.Duration(0.5)
                self.marker_pub.publish(mk)
        if self.image_pub is not None:
            import cv2

            canvas = bgr.copy()
            for i, c in enumerate(circles):
                colour = (0, 255, 0) if i == middle else (0, 0, 255)
                cv2.circle(canvas, (int(round(c.u)), int(round(c.v))), int(round(c.radius_px)), colour, 2)
                cv2.circle(canvas, (int(round(c.u)), int(round(c.v))), 3, colour, -1)
            img = Image(header=color.header, height=canvas.shape[0], width=canvas.shape[1], encoding="bgr8",
                        is_bigendian=0, step=canvas.shape[1] * 3, data=canvas.tobytes())
            self.image_pub.publish(img)
