"""ROS adapter of FireDetector: topics, the CheckFire service and the debug outputs of one camera."""
from __future__ import annotations

import threading
from typing import Optional, Tuple

import cv2
import numpy as np
import rospy
from rospy.numpy_msg import numpy_msg
from geometry_msgs.msg import PoseStamped
from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList, ThermalImage
from mbzirc_comm_objs.srv import CheckFire, CheckFireResponse
from sensor_msgs.msg import Image, LaserScan, Temperature
from std_msgs.msg import Float64MultiArray

from fire_detector import constants as C
from fire_detector.detector import DetectorConfig, FireDetector, FrameResult
from fire_detector.geometry import front_laser_range, laser_range_along, uav_heading

THROTTLE_S = 5.0
DEBUG_IMAGE_SCALE = 8


class FireDetectorNode:
    """Subscribes the thermal array, the pose and the laser of one robot; publishes its fires.

    Every name is relative, so the node runs inside the robot's namespace (`/mbzirc2020_<id>/`).

    .. note:: `debug_view` of the original opened an OpenCV window; this headless port publishes the same
       view (colour image x8 with the centroid) on `thermal_detection/debug_image` instead.
    """

    def __init__(self) -> None:
        self.uav_id = str(rospy.get_param("~uav_id", C.DEFAULT_UAV_ID))
        self.frame_id = str(rospy.get_param("~frame_id", "arena"))
        # Height of the thermal camera above the robot's pose origin (extension: 0 on a UAV, as the
        # original assumed; a UGV carries it on a mast, and fires are placed from the camera, not the chassis).
        self.camera_height = float(rospy.get_param("~camera_height", 0.0))
        if not np.isfinite(self.camera_height):
            rospy.logerr("fire_detector: ~camera_height is not finite, using 0")
            self.camera_height = 0.0
        self.covariance = (
            float(rospy.get_param("~covariance_x", C.DEFAULT_COVARIANCE_X)),
            float(rospy.get_param("~covariance_y", C.DEFAULT_COVARIANCE_Y)),
            float(rospy.get_param("~covariance_z", C.DEFAULT_COVARIANCE_Z)),
        )
        self.debug_view = bool(rospy.get_param("~debug_view", False))
        self.debug_publisher = bool(rospy.get_param("~debug_publisher", False))
        config = DetectorConfig(
            camera_config=str(rospy.get_param("~camera_config", C.DEFAULT_CAMERA_CONFIG)).upper(),
            thermal_threshold=float(rospy.get_param("~thermal_threshold", C.DEFAULT_THERMAL_THRESHOLD)),
            angle_amplitude=float(rospy.get_param("~angle_amplitude", C.DEFAULT_ANGLE_AMPLITUDE_DEG)),
            num_frame_filter=int(rospy.get_param("~num_frame_filter", C.DEFAULT_NUM_FRAME_FILTER)),
            false_negative_tolerance=int(rospy.get_param("~false_negative_tolerance", C.DEFAULT_FALSE_NEGATIVE_TOLERANCE)),
            min_contrast=float(rospy.get_param("~min_contrast", C.DEFAULT_MIN_CONTRAST)),
            saturation_temperature=float(rospy.get_param("~saturation_temperature", C.DEFAULT_SATURATION_TEMPERATURE)),
            band_max_fill=float(rospy.get_param("~band_max_fill", C.DEFAULT_BAND_MAX_FILL)),
            hot_frame_max_range=float(rospy.get_param("~hot_frame_max_range", C.HOT_FRAME_MAX_RANGE)),
            check_fire_max_range=float(rospy.get_param("~check_fire_max_range", C.MAX_LASER_RANGE_FIRE)),
        )
        if rospy.has_param("~min_fire_temperature"):
            rospy.logwarn("fire_detector: ~min_fire_temperature is gone (a fixed floor cannot tell a fire from a "
                          "sun-heated wall); ignored, see ~min_contrast and ~saturation_temperature")
        self.detector = FireDetector(config)
        self.lock = threading.Lock()
        self.pose: Optional[Tuple[Tuple[float, float, float], float]] = None
        self.laser_range: Optional[float] = None
        self.scan: Optional[LaserScan] = None     # the latest, for the range along a hot spot's bearing
        self.last_spot = None

        self.pub = rospy.Publisher("sensed_objects", ObjectDetectionList, queue_size=1)
        self.debug_pub = rospy.Publisher("thermal_detection/debug", Temperature, queue_size=1) if self.debug_publisher else None
        self.debug_img_pub = rospy.Publisher("thermal_detection/debug_image", Image, queue_size=1) if self.debug_view else None
        self.srv = rospy.Service("thermal_detection/fire_detected", CheckFire, self.on_check_fire)
        rospy.Subscriber("ual/pose", PoseStamped, self.on_pose, queue_size=1)
        if config.camera_direction == C.CAMERA_DIRECTION_FORWARD:
            # numpy_msg: the arrays arrive as numpy views of the message bytes, not tuples of Python floats
            # (720 ranges at 10 Hz, 1024 temperatures at 14 Hz: the node's main cost before)
            rospy.Subscriber("scan", numpy_msg(LaserScan), self.on_scan, queue_size=1)
        rospy.Subscriber("teraranger_evo_thermal/raw_temp_array", numpy_msg(Float64MultiArray), self.on_temperatures,
                         queue_size=5)
        if self.debug_view:
            rospy.Subscriber("teraranger_evo_thermal/rgb_image", Image, self.on_rgb_image, queue_size=1)
        rospy.loginfo("fire_detector: %s camera, threshold %.1f degC, filter %d frames",
                      config.camera_config, config.thermal_threshold, config.num_frame_filter)

    # ---- inputs --------------------------------------------------------------------------------------
    def on_pose(self, msg: PoseStamped) -> None:
        p, q = msg.pose.position, msg.pose.orientation
        vals = (p.x, p.y, p.z, q.x, q.y, q.z, q.w)
        if not all(np.isfinite(vals)):
            rospy.logerr_throttle(THROTTLE_S, "fire_detector: non-finite ual/pose ignored")
            return
        with self.lock:
            self.pose = ((p.x, p.y, p.z + self.camera_height), uav_heading(q.x, q.y, q.z, q.w))

    def on_scan(self, msg: LaserScan) -> None:
        rng = front_laser_range(msg.ranges, msg.angle_min, msg.angle_increment, msg.range_min,
                                msg.range_max, self.detector.config.angle_amplitude)
        if rng is None:
            if (len(msg.ranges) == 0 or not np.isfinite(msg.angle_increment) or msg.angle_increment == 0.0
                    or msg.range_min > msg.range_max
                    or np.isnan(np.asarray(msg.ranges, dtype=float)).all()):
                # a few NaN beams are a real laser's dropouts (1-2 % under `realistic`), not a bad scan
                rospy.logerr_throttle(THROTTLE_S, "fire_detector: malformed scan (no ranges, every beam NaN or "
                                                  "bad angles)")
            else:   # nothing within range ahead (open sky, on the ground): normal, only no forward fire
                rospy.logdebug_throttle(THROTTLE_S, "fire_detector: nothing within laser range ahead")
        with self.lock:
            self.laser_range = rng
            self.scan = msg

    def _range_along(self, scan: LaserScan):
        """bearing -> the scan's range along it (geometry.laser_range_along)."""
        return lambda bearing: laser_range_along(scan.ranges, scan.angle_min, scan.angle_increment, scan.range_min,
                                                 scan.range_max, bearing, self.detector.config.angle_amplitude)

    def on_temperatures(self, msg: Float64MultiArray) -> None:
        with self.lock:
            pose, laser, scan = self.pose, self.laser_range, self.scan
            try:
                result = self.detector.process(msg.data, pose[0] if pose else None, pose[1] if pose else None, laser,
                                               None if scan is None else self._range_along(scan))
            except ValueError as err:
                rospy.logerr_throttle(THROTTLE_S, f"fire_detector: bad raw_temp_array: {err}")
                return
            self.last_spot = result.spot
        stamp = rospy.Time.now()
        if self.debug_pub is not None:
            self.publish_debug(result, stamp)
        if result.fire is None:
            if result.confirmed and result.spot is not None:
                rospy.logwarn_throttle(THROTTLE_S, f"fire_detector: fire seen but not placed: {result.reason}")
            return
        self.pub.publish(self.to_message(result, stamp))

    def on_rgb_image(self, msg: Image) -> None:
        if msg.encoding not in ("rgb8", "bgr8") or msg.width * msg.height * 3 != len(msg.data) or msg.width == 0:
            rospy.logerr_throttle(THROTTLE_S, f"fire_detector: rgb_image must be rgb8/bgr8 with matching size, got {msg.encoding} {msg.width}x{msg.height}")
            return
        img = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.width, 3)
        big = cv2.resize(img, (msg.width * DEBUG_IMAGE_SCALE, msg.height * DEBUG_IMAGE_SCALE), interpolation=cv2.INTER_NEAREST)
        spot = self.last_spot
        if spot is not None:
            sx, sy = msg.width / C.IMG_WIDTH * DEBUG_IMAGE_SCALE, msg.height / C.IMG_HEIGHT * DEBUG_IMAGE_SCALE
            centre = (int((spot.u + 0.5) * sx), int((spot.v + 0.5) * sy))
            cv2.drawMarker(big, centre, (0, 255, 0), cv2.MARKER_CROSS, 20, 2)
        out = Image(header=msg.header, height=big.shape[0], width=big.shape[1], encoding=msg.encoding,
                    is_bigendian=0, step=big.shape[1] * 3, data=big.tobytes())
        self.debug_img_pub.publish(out)

    def on_check_fire(self, _req) -> CheckFireResponse:
        with self.lock:
            return CheckFireResponse(fire_detected=self.detector.fire_detected)

    # ---- outputs -------------------------------------------------------------------------------------
    def publish_debug(self, result: FrameResult, stamp: rospy.Time) -> None:
        """Hottest pixel of the frame (NaN when nothing is hot), variance = 0 when a fire is confirmed."""
        t = Temperature()
        t.header.stamp = stamp
        t.header.frame_id = f"mbzirc2020_{self.uav_id}/thermal_link"
        t.temperature = result.spot.max_temperature if result.spot else float("nan")
        t.variance = 0.0 if result.confirmed else 1.0
        self.debug_pub.publish(t)

    def to_message(self, result: FrameResult, stamp: rospy.Time) -> ObjectDetectionList:
        fire, spot, cfg = result.fire, result.fire.spot, self.detector.config
        det = ObjectDetection()
        det.header.stamp = stamp
        det.header.frame_id = self.frame_id
        det.type = ObjectDetection.TYPE_FIRE
        det.color = ObjectDetection.COLOR_FIRE
        det.pose.pose.position.x, det.pose.pose.position.y, det.pose.pose.position.z = fire.position
        det.pose.pose.orientation.w = 1.0
        cov = [0.0] * 36
        cov[0], cov[7], cov[14] = (s * s for s in self.covariance)   # the original: covariance_x is a std (m)
        det.pose.covariance = cov
        det.relative_position.x, det.relative_position.y, det.relative_position.z = fire.relative_position
        det.relative_yaw = float(np.arctan2(fire.relative_position[1], fire.relative_position[0])) \
            if cfg.camera_direction == C.CAMERA_DIRECTION_FORWARD else 0.0
        size_m = max(spot.width, spot.height) * fire.depth / C.FOCAL_PX
        det.scale.x = det.scale.y = det.scale.z = size_m
        # u, v, width, height as the original sets them: offsets of the centroid from the image centre
        # (u towards the image left, v towards its bottom, pixels) and its fixed spot size
        det.image_detection = ThermalImage(camera_direction=cfg.camera_direction, img_height=C.IMG_HEIGHT,
                                           img_width=C.IMG_WIDTH, u=C.CENTER_U - spot.u, v=spot.v - C.CENTER_V,
                                           height=C.ORIGINAL_SPOT_SIZE_PX, width=C.ORIGINAL_SPOT_SIZE_PX,
                                           depth=fire.depth)
        return ObjectDetectionList(agent_id=self.uav_id, stamp=stamp, objects=[det])
