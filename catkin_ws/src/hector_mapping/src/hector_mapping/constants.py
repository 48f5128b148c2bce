"""Every constant of the package in one place: node parameter defaults and the algorithm's fixed numbers.

The parameter names and defaults are the original hector_mapping node's, so that launch files written for
it (like the thesis's) work unchanged. The thesis launch overrides some of them (see
mbzirc_launchers/launch/c3_slam.launch).
"""
from __future__ import annotations

#: ``~`` parameters of the node and their defaults (the original node's defaults).
NODE_PARAM_DEFAULTS: dict[str, object] = {
    "base_frame": "base_link",
    "map_frame": "map",
    "odom_frame": "odom",
    "map_resolution": 0.025,
    "map_size": 1024,
    "map_start_x": 0.5,
    "map_start_y": 0.5,
    "map_multi_res_levels": 3,
    "update_factor_free": 0.4,
    "update_factor_occupied": 0.9,
    "map_update_distance_thresh": 0.4,
    "map_update_angle_thresh": 0.9,
    "laser_min_dist": 0.4,
    "laser_max_dist": 30.0,
    "laser_z_min_value": -1.0,
    "laser_z_max_value": 1.0,
    "pub_map_odom_transform": True,
    "pub_map_scanmatch_transform": True,
    "pub_odometry": False,
    "use_tf_scan_transformation": True,
    "use_tf_pose_start_estimate": False,
    "map_pub_period": 2.0,
    "advertise_map_service": True,
    "tf_map_scanmatch_transform_frame_name": "scanmatcher_frame",
    "scan_topic": "scan",
    "scan_subscriber_queue_size": 5,
    "pub_drawings": False,
    # not in the original (README, "beyond the original"): a frame in which base_frame's yaw is measured by
    # another sensor (IMU / compass, e.g. the UAL's pose frame); each match starts from the last yaw turned
    # by that yaw's change since the last scan. "" = off (the original's start: the last pose)
    "yaw_prior_frame": "",
    "pub_debug_output": False,
    # not in the original (README, "beyond the original"): publish `map` (and answer dynamic_map) with the
    # box of the cells scans have touched only, its origin moved to the box's corner. False = the original's
    # whole map_size x map_size grid
    "map_pub_known_area": False,
}

#: Log-odds values are clamped to +-this so that a cell can still change its mind after many scans and
#: exp() never overflows.
LOG_ODDS_LIMIT = 50.0

#: Gauss-Newton iterations per scan on the coarse levels and on the finest level (the original's counts).
ITERATIONS_COARSE = 4
ITERATIONS_FINE = 6

#: While a step is still larger than STEP_TOLERANCE (m and rad), iterate up to this many times the
#: nominal count: the probability field of a grid is flat away from the walls, so Gauss-Newton
#: converges slowly in rotation after a fast turn and the nominal count stops short of the minimum.
ITERATION_EXTENSION = 3
STEP_TOLERANCE = 2e-4

#: Rotation offsets (rad) tried around the initial guess on the coarsest level before Gauss-Newton: a
#: turn of 0.07 rad between scans (1 rad/s at 15 Hz) moves points 5 m away by several fine cells, outside
#: the basin of the bilinear field; the best-fitting offset puts the matcher back inside it.
ROTATION_SEARCH_OFFSETS = (-0.16, -0.12, -0.08, -0.04, 0.0, 0.04, 0.08, 0.12, 0.16)
#: Another start only replaces the predicted pose when its residual is lower by more than this fraction.
START_MARGIN = 0.05

#: Largest rotation (rad) a single Gauss-Newton step may make: a step larger than this is almost always
#: the linearisation running away, not the true motion.
MAX_ROTATION_STEP = 0.2

#: Recovery search: when a match fits much worse than the recent ones (residual above RECOVERY_FACTOR
#: times their running mean and above RECOVERY_MIN_RESIDUAL), candidate poses on a grid of
#: RECOVERY_TRANSLATIONS x RECOVERY_TRANSLATIONS x RECOVERY_ROTATIONS offsets around the prediction are
#: scored on the coarsest level in one batch, the RECOVERY_CANDIDATES best are matched coarse-to-fine, and
#: the best fit wins (the first match included). It catches a match that fell out of its basin after
#: dropped scans or a sudden change of motion, at no cost while tracking is good.
RECOVERY_FACTOR = 3.0
RECOVERY_MIN_RESIDUAL = 0.05
RECOVERY_TRANSLATIONS = (-0.3, -0.15, 0.0, 0.15, 0.3)
RECOVERY_ROTATIONS = (-0.4, -0.3, -0.2, -0.1, 0.0, 0.1, 0.2, 0.3, 0.4)
RECOVERY_CANDIDATES = 3
#: Weight of a new residual in the running mean the recovery test compares with.
RESIDUAL_AVERAGE_WEIGHT = 0.1

#: A scan with fewer usable points than this is not matched (the matching problem is under-determined).
MIN_SCAN_POINTS = 10

#: Scans whose angle count disagrees with (angle_max - angle_min) / angle_increment by more than this are
#: rejected as malformed (1 allows both the "closed" and the "half-open" 360 degree conventions).
ANGLE_COUNT_TOLERANCE = 1

#: Floor added to the diagonal of the published pose covariance (m^2, m^2, rad^2): the Hessian-based
#: estimate is optimistic when the scan fits perfectly.
COVARIANCE_FLOOR = (1e-6, 1e-6, 1e-6)

#: Values of nav_msgs/OccupancyGrid cells.
OCC_OCCUPIED = 100
OCC_FREE = 0
OCC_UNKNOWN = -1
