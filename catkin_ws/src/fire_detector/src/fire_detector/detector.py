"""One thermal camera's fire detector without ROS: frame -> hot spot -> frame filter -> fire position."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence, Tuple

import numpy as np

from fire_detector import constants as C
from fire_detector.frame_filter import FrameFilter
from fire_detector.geometry import downward_fire_position, forward_fire_position, spot_bearing
from fire_detector.thermal import HotSpot, find_hot_spot, parse_temperatures

Vec3 = Tuple[float, float, float]


@dataclass
class DetectorConfig:
    """Parameters of FireDetector (the node's `~` params): the original's names, defaults and meaning first,
    then what this port adds (README.md, "beyond the original"; their neutral values give the original)."""

    camera_config: str = C.DEFAULT_CAMERA_CONFIG
    thermal_threshold: float = C.DEFAULT_THERMAL_THRESHOLD
    angle_amplitude: float = C.DEFAULT_ANGLE_AMPLITUDE_DEG
    num_frame_filter: int = C.DEFAULT_NUM_FRAME_FILTER
    # beyond the original
    false_negative_tolerance: int = C.DEFAULT_FALSE_NEGATIVE_TOLERANCE
    min_contrast: float = C.DEFAULT_MIN_CONTRAST
    saturation_temperature: float = C.DEFAULT_SATURATION_TEMPERATURE
    band_max_fill: float = C.DEFAULT_BAND_MAX_FILL
    hot_frame_max_range: float = C.HOT_FRAME_MAX_RANGE      # the original's fixed 5 m, as a parameter
    check_fire_max_range: float = C.MAX_LASER_RANGE_FIRE    # the original's 7.5 m, as a parameter

    def __post_init__(self) -> None:
        if self.camera_config not in C.CAMERA_CONFIGS:
            raise ValueError(f"camera_config must be one of {sorted(C.CAMERA_CONFIGS)}, got {self.camera_config!r}")

    @property
    def camera_direction(self) -> int:
        return C.CAMERA_CONFIGS[self.camera_config]


@dataclass
class Fire:
    """A confirmed fire in one frame.

    Args:
        position: arena-frame position (m).
        relative_position: body-frame offset from the UAV (x forward, y left, z up).
        depth: laser range (FORWARD) or height above the ground (DOWNWARD), metres.
        spot: the hot spot in the image it comes from.
    """

    position: Vec3
    relative_position: Vec3
    depth: float
    spot: HotSpot


@dataclass
class FrameResult:
    """What one frame produced: the hot spot (if any), the filter state, the fire (if placed) and why not."""

    spot: Optional[HotSpot]
    confirmed: bool
    fire: Optional[Fire] = None
    reason: str = ""


class FireDetector:
    """Threshold -> contours -> centroid, frame filter, then placement from the pose and the laser.

    Args:
        config: the detector parameters.

    .. note:: a confirmed fire with no usable pose or (FORWARD) no valid front laser range keeps the filter
       confirmed (CheckFire says yes) but gives no position; beyond the 7.5 m gate CheckFire says no.
    """

    def __init__(self, config: DetectorConfig) -> None:
        self.config = config
        self.filter = FrameFilter(config.num_frame_filter, config.false_negative_tolerance)
        self.within_check_range = True

    @property
    def fire_detected(self) -> bool:
        """The CheckFire answer: the frame filter believes in a fire and (FORWARD) the wall ahead is within
        the 7.5 m gate."""
        return self.filter.confirmed and self.within_check_range

    def _laser_gate(self, laser_range: Optional[float], limit: float) -> bool:
        """FORWARD: the front range is under `limit` (or no valid beam ahead, as the original's 0 mean)."""
        if self.config.camera_direction != C.CAMERA_DIRECTION_FORWARD:
            return True
        return laser_range is None or not math.isfinite(laser_range) or laser_range < limit

    def _forward_depth(self, laser_range: float, range_along, spot: HotSpot) -> Optional[float]:
        """How far ahead (along the camera's axis) the fire is: the laser's range along the spot's bearing
        projected on the axis, or the front range without range_along. Why (UGV exploring with GNSS off):
        a fire 15 deg off the axis on a wall seen at a grazing angle, the front beam on a nearer wall, was
        placed on that wall, 2.8 m from the fire. None: no return along the bearing within
        ~check_fire_max_range (looking out through a gap: the front wall is not the fire's)."""
        if range_along is None:
            return laser_range
        bearing = spot_bearing(spot.u)
        r = range_along(bearing)
        if r is None or not math.isfinite(r) or r >= self.config.check_fire_max_range:
            return None
        return r * math.cos(bearing)

    def process(
        self,
        temperatures: Sequence[float],
        uav_position: Optional[Vec3],
        uav_yaw: Optional[float],
        laser_range: Optional[float],
        range_along: Optional[Callable[[float], Optional[float]]] = None,
    ) -> FrameResult:
        """Processes one raw_temp_array frame; raises ValueError on malformed temperatures.

        range_along (FORWARD): the laser's range along a bearing (rad, left positive), to place the fire at
        the range along the spot's bearing instead of the front range (`_forward_depth`); None: the front
        range, as the original."""
        cfg = self.config
        frame = parse_temperatures(temperatures)
        spot = find_hot_spot(frame, cfg.thermal_threshold, cfg.min_contrast, cfg.saturation_temperature,
                             cfg.band_max_fill)
        near = self._laser_gate(laser_range, cfg.hot_frame_max_range)
        confirmed_now = self.filter.update(spot is not None and near)
        self.within_check_range = self._laser_gate(laser_range, cfg.check_fire_max_range)
        result = FrameResult(spot=spot, confirmed=self.fire_detected)
        if spot is None:
            result.reason = "no hot spot"
            return result
        if not near:
            result.reason = (f"hot, but the front laser range {laser_range:.2f} m >= {cfg.hot_frame_max_range} m "
                             "(hot frames count only closer)")
            return result
        if not confirmed_now:
            result.reason = f"filtering ({self.filter.hot_count}/{self.filter.num_frame_filter + 1} hot frames)"
            return result
        if uav_position is None or uav_yaw is None or not all(map(math.isfinite, (*uav_position, uav_yaw))):
            result.reason = "no valid UAV pose"
            return result
        if self.config.camera_direction == C.CAMERA_DIRECTION_FORWARD:
            if laser_range is None or not math.isfinite(laser_range):
                result.reason = "no valid front laser range"
                return result
            if laser_range >= cfg.check_fire_max_range:
                result.reason = f"front laser range {laser_range:.2f} m >= {cfg.check_fire_max_range} m"
                return result
            depth = self._forward_depth(laser_range, range_along, spot)
            if depth is None:
                result.reason = (f"no laser return along the spot's bearing "
                                 f"({math.degrees(spot_bearing(spot.u)):+.0f} deg)")
                return result
            pos, rel = forward_fire_position(uav_position, uav_yaw, depth, spot.u, spot.v)
        else:
            pos, rel = downward_fire_position(uav_position, uav_yaw, spot.u, spot.v)
            depth = -rel[2]
        result.fire = Fire(position=pos, relative_position=rel, depth=depth, spot=spot)
        result.reason = "fire"
        return result
