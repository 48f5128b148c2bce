"""Placing a fire in the arena frame: laser range ahead (FORWARD) or the ground below (DOWNWARD)."""
from __future__ import annotations

import math
from typing import Optional, Sequence, Tuple

import numpy as np
from mbzirc_arena.yaw import yaw_from_quaternion

from fire_detector import constants as C

Vec3 = Tuple[float, float, float]


def uav_heading(x: float, y: float, z: float, w: float) -> float:
    """Yaw (rad) of the UAV's orientation (the thermal geometry only uses its heading); 0 for the all-zero
    quaternion of a pose that carries no orientation."""
    yaw = yaw_from_quaternion(x, y, z, w)
    return 0.0 if yaw is None else yaw


def front_laser_range(
    ranges: Sequence[float],
    angle_min: float,
    angle_increment: float,
    range_min: float,
    range_max: float,
    angle_amplitude_deg: float,
) -> Optional[float]:
    """Mean range of the valid beams within +-angle_amplitude_deg of the front (angle 0) beam.

    The original summed every beam of the window and divided by the window size, so NaN, inf or
    out-of-range beams corrupted the mean; here only finite beams inside [range_min, range_max] count.
    Returns None when the window holds no valid beam or the scan geometry is malformed.
    """
    valid = _valid_beams_around(ranges, angle_min, angle_increment, range_min, range_max, 0.0, angle_amplitude_deg)
    return None if valid is None else float(valid.mean())


def laser_range_along(
    ranges: Sequence[float],
    angle_min: float,
    angle_increment: float,
    range_min: float,
    range_max: float,
    bearing: float,
    angle_amplitude_deg: float,
) -> Optional[float]:
    """Median range of the valid beams within +-angle_amplitude_deg of `bearing` (rad, laser frame, left
    positive); None when there is none. The median: a doorway's edge inside the window mixes two walls,
    whose mean lies on neither."""
    valid = _valid_beams_around(ranges, angle_min, angle_increment, range_min, range_max, bearing,
                                angle_amplitude_deg)
    return None if valid is None else float(np.median(valid))


def _valid_beams_around(ranges, angle_min, angle_increment, range_min, range_max, bearing, amplitude_deg):
    """The finite beams inside [range_min, range_max] within +-amplitude_deg of bearing; None if none or
    the scan geometry is malformed."""
    r = np.asarray(ranges, dtype=np.float64)
    if r.size == 0 or not math.isfinite(angle_increment) or angle_increment == 0.0 or not math.isfinite(angle_min):
        return None
    centre = int(round((bearing - angle_min) / angle_increment))
    half = int(math.floor(math.radians(abs(amplitude_deg)) / abs(angle_increment) + 1e-9))
    lo, hi = max(0, centre - half), min(r.size, centre + half + 1)
    if lo >= hi:
        return None
    window = r[lo:hi]
    lo_ok = range_min if math.isfinite(range_min) else 0.0
    hi_ok = range_max if math.isfinite(range_max) and range_max > 0 else np.inf
    valid = window[np.isfinite(window) & (window >= lo_ok) & (window <= hi_ok)]
    return valid if valid.size else None


def spot_bearing(u: float) -> float:
    """Bearing (rad, left positive) of the image column u from the camera's axis."""
    return math.atan2(-(u - C.CENTER_U), C.FOCAL_PX)


def _to_arena(uav: Vec3, yaw: float, body: Vec3) -> Vec3:
    c, s = math.cos(yaw), math.sin(yaw)
    return (uav[0] + c * body[0] - s * body[1], uav[1] + s * body[0] + c * body[1], uav[2] + body[2])


def forward_fire_position(uav: Vec3, yaw: float, laser_range: float, u: float, v: float) -> Tuple[Vec3, Vec3]:
    """Fire on the wall ahead: `laser_range` metres along the heading, shifted by the pixel bearing.

    Returns (arena position, body-frame relative position). The original put the fire straight ahead;
    the pixel bearing of the centroid places it where the camera sees it (a fire 10 px off-centre at
    4 m is 0.7 m to the side).
    """
    left = -(u - C.CENTER_U) / C.FOCAL_PX * laser_range
    up = -(v - C.CENTER_V) / C.FOCAL_PX * laser_range
    rel = (laser_range, left, up)
    return _to_arena(uav, yaw, rel), rel


def downward_fire_position(uav: Vec3, yaw: float, u: float, v: float, ground_z: float = C.GROUND_Z) -> Tuple[Vec3, Vec3]:
    """Fire on the ground under the UAV, shifted by the pixel bearing (image top = UAV front).

    Returns (arena position, body-frame relative position); the height above the ground is the depth.
    """
    h = max(0.0, uav[2] - ground_z)
    fwd = -(v - C.CENTER_V) / C.FOCAL_PX * h
    left = -(u - C.CENTER_U) / C.FOCAL_PX * h
    rel = (fwd, left, -h)
    return _to_arena(uav, yaw, rel), rel
