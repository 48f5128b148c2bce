"""Pure controllers of the tasks: centring a hole at the nozzle, centring a ground fire under the UAV,
centring on a window or door and going through it.

Why pure: the loops run at a fixed rate in the tasks; their maths (frames, gains, saturation, when
"centred" holds) is tested here without a simulator.
Frames: body = base_link (x forward, y left, z up); world = arena. Velocities are returned in the world
frame, as `ual/set_velocity` takes them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np


def body_to_world(v_body: Sequence[float], yaw: float) -> np.ndarray:
    """Rotate a body-frame vector into the world frame (yaw only: the UAV flies level)."""
    c, s = math.cos(yaw), math.sin(yaw)
    x, y, z = v_body
    return np.array([c * x - s * y, s * x + c * y, z])


def world_to_body(v_world: Sequence[float], yaw: float) -> np.ndarray:
    """Inverse of body_to_world."""
    c, s = math.cos(yaw), math.sin(yaw)
    x, y, z = v_world
    return np.array([c * x + s * y, -s * x + c * y, z])


def saturate(v: np.ndarray, vmax: float) -> np.ndarray:
    """v scaled down so that its norm is at most vmax."""
    n = float(np.linalg.norm(v))
    return v if n <= vmax or n == 0 else v * (vmax / n)


@dataclass
class HoleCentering:
    """P controller that brings a hole (body frame position) in front of the nozzle.

    Args:
        shoot_distance: wanted distance (m, along body x) from the UAV centre to the hole.
        nozzle_offset: (y, z) of the water jet's aim in the body frame at that distance.
        gain: 1/s; vmax: m/s; tolerance: m of lateral/vertical error that counts as centred;
        depth_tolerance: m of error along x that counts as centred.
    """
    shoot_distance: float = 1.5
    nozzle_offset: Tuple[float, float] = (0.0, 0.0)
    gain: float = 0.8
    vmax: float = 0.5
    tolerance: float = 0.15
    depth_tolerance: float = 0.4

    def error(self, hole_body: Sequence[float]) -> np.ndarray:
        """Body-frame error (how far the UAV must move) to put the hole at the aim point."""
        return np.array([hole_body[0] - self.shoot_distance, hole_body[1] - self.nozzle_offset[0],
                         hole_body[2] - self.nozzle_offset[1]])

    def centred(self, hole_body: Sequence[float]) -> bool:
        """True when the jet would hit the hole."""
        e = self.error(hole_body)
        return abs(e[1]) <= self.tolerance and abs(e[2]) <= self.tolerance and abs(e[0]) <= self.depth_tolerance

    def velocity(self, hole_body: Sequence[float], yaw: float, front_range: float = math.inf,
                 min_wall: float = 0.0) -> np.ndarray:
        """World-frame velocity command that reduces the error.

        Why front_range: the hole estimate may be metres off (decoys, a stale estimate) and would pull the
        UAV into the facade; the laser range ahead says where the wall really is, so the forward set-point
        (here + error along x) is clamped to stay at least min_wall from it (a negative error backs off).
        """
        e = self.error(hole_body)
        if math.isfinite(front_range):
            e[0] = min(e[0], front_range - min_wall)
        return body_to_world(saturate(self.gain * e, self.vmax), yaw)


def front_distance(ranges: Sequence[float], angle_min: float, angle_increment: float,
                   half_width: float = 0.26) -> float:
    """Distance ahead to the nearest return of a LaserScan within +-half_width rad of the front, as its
    component along the heading (r cos a: the facade plane's distance when facing it). inf when no beam
    there has a finite positive range (nothing ahead, or a scan without usable data).

    Several beams, not only the front one: the front beam may pass through the hole being aimed at.
    """
    if not math.isfinite(angle_min) or not math.isfinite(angle_increment) or angle_increment <= 0:
        return math.inf
    r = np.asarray(ranges, dtype=float)
    if r.size == 0:
        return math.inf
    a = angle_min + angle_increment * np.arange(r.size)
    a = np.arctan2(np.sin(a), np.cos(a))
    ok = (np.abs(a) <= half_width) & np.isfinite(r) & (r > 0)
    if not ok.any():
        return math.inf
    return float(np.min(r[ok] * np.cos(a[ok])))


def nearest_return(ranges: Sequence[float], angle_min: float, angle_increment: float,
                   range_min: float = 0.0) -> Tuple[float, float]:
    """(distance, body angle) of the closest valid return of a LaserScan, (inf, 0) when none. The laser
    measures the walls around the robot as they are, whatever its GNSS error (the arena model placed
    with the reported pose may be a metre off)."""
    r = np.asarray(ranges, dtype=float)
    if r.size == 0 or not math.isfinite(angle_min) or not math.isfinite(angle_increment):
        return math.inf, 0.0
    ok = np.isfinite(r) & (r > max(0.0, range_min))
    if not ok.any():
        return math.inf, 0.0
    i = int(np.argmin(np.where(ok, r, np.inf)))
    return float(r[i]), float(angle_min + angle_increment * i)


def keep_off_return(v: Sequence[float], yaw: float, distance: float, body_angle: float,
                    min_dist: float) -> np.ndarray:
    """v without its component toward the laser's nearest return when closer than min_dist (and a push
    away when closer than 0.8 x min_dist)."""
    v = np.array(v, dtype=float)
    if not math.isfinite(distance) or distance >= min_dist:
        return v
    a = yaw + body_angle
    toward_dir = np.array([math.cos(a), math.sin(a), 0.0])
    toward = float(v @ toward_dir)
    if toward > 0:
        v = v - toward * toward_dir
    if distance < 0.8 * min_dist:
        v = v - 0.3 * toward_dir
    return v


def thermal_pixel_to_ground(u: float, v: float, height: float, width_px: int = 32, height_px: int = 32,
                            fov_deg: float = 33.0) -> np.ndarray:
    """Body-frame (x, y) offset on the ground of pixel (u, v) of the DOWNWARD thermal camera.

    Image top = UAV front, image right = UAV right (-y). `height` is the camera's height above ground.
    """
    f = (width_px / 2.0) / math.tan(math.radians(fov_deg) / 2.0)
    du = (u - (width_px - 1) / 2.0) / f
    dv = (v - (height_px - 1) / 2.0) / f
    return np.array([-dv * height, -du * height])


@dataclass
class GroundFireCentering:
    """Centre a ground fire under the UAV while descending to a release height.

    Horizontal: P on the world xy error; vertical: descend at `descent_speed` only while the horizontal
    error is under `descend_tolerance`, so the UAV never drops off-target.
    """
    release_height: float = 1.5
    gain: float = 0.8
    vmax: float = 0.6
    descent_speed: float = 0.4
    tolerance: float = 0.25
    descend_tolerance: float = 0.6

    def velocity(self, uav: Sequence[float], fire_xy: Sequence[float], ground_z: float = 0.0) -> np.ndarray:
        """World velocity toward being over fire_xy at release height."""
        exy = np.array([fire_xy[0] - uav[0], fire_xy[1] - uav[1]])
        vxy = saturate(self.gain * exy, self.vmax)
        dz = (ground_z + self.release_height) - uav[2]
        if np.linalg.norm(exy) <= self.descend_tolerance:
            vz = float(np.clip(self.gain * dz, -self.descent_speed, self.descent_speed))
        else:
            vz = float(np.clip(self.gain * dz, 0.0, self.descent_speed))   # may climb, never descend
        return np.array([vxy[0], vxy[1], vz])

    def ready(self, uav: Sequence[float], fire_xy: Sequence[float], ground_z: float = 0.0) -> bool:
        """True when over the fire within tolerance and at release height (+-0.3 m)."""
        exy = math.hypot(fire_xy[0] - uav[0], fire_xy[1] - uav[1])
        return exy <= self.tolerance and abs(uav[2] - (ground_z + self.release_height)) <= 0.3


@dataclass
class OpeningPassage:
    """Body-frame velocity (vx, vy) that centres the robot on an opening in the wall ahead (a window, a
    door: openings.SeenOpening), then takes it through with the lateral correction still applied.

    Args:
        standoff: m from the wall the robot keeps at least while centring (it backs off when closer: the
            GNSS error may have put it nearer than planned); gain: 1/s; lateral_vmax: m/s sideways (and
            backing off); speed: m/s forward through; tolerance: m off the opening's middle that counts as
            centred. Through, forward motion stops while the robot is further off the middle than the room
            the opening leaves it (`through`'s room).
    """
    standoff: float = 1.0
    gain: float = 1.0
    lateral_vmax: float = 0.4
    speed: float = 0.4
    tolerance: float = 0.12

    def centred(self, lateral: float, distance: float) -> bool:
        """True when the opening's middle is straight ahead and the wall no nearer than the standoff."""
        return abs(lateral) <= self.tolerance and distance >= self.standoff - self.tolerance

    def centring(self, lateral: float, distance: float) -> np.ndarray:
        """Sideways onto the opening's middle, backing off when nearer than the standoff (never forward)."""
        vx = self.gain * min(0.0, distance - self.standoff)
        return saturate(np.array([vx, self.gain * lateral]), self.lateral_vmax)

    def through(self, lateral: Optional[float], room: Optional[float] = None,
                speed: Optional[float] = None) -> np.ndarray:
        """Forward at `speed` (default: the passage's), sideways onto the middle when it is seen (None:
        straight on). Forward only while |lateral| <= room: room (m) is how far off its middle the opening
        lets the robot be (passage.py: its half width less the robot's frame and a margin); unknown room
        (None, NaN): twice the tolerance. Never forward when off by more than the room, however small the
        room (a narrow opening: the frame would meet its edge)."""
        speed = self.speed if speed is None else speed
        if lateral is None or not math.isfinite(lateral):
            return np.array([speed, 0.0])
        vy = float(np.clip(self.gain * lateral, -self.lateral_vmax, self.lateral_vmax))
        allowed = 2.0 * self.tolerance if room is None or not math.isfinite(room) else room
        vx = speed if abs(lateral) <= allowed else 0.0
        return np.array([vx, vy])


def yaw_rate_to(current_yaw: float, target_yaw: float, gain: float = 1.0, max_rate: float = 0.8) -> float:
    """Yaw rate (rad/s) that turns toward target_yaw the short way."""
    e = math.atan2(math.sin(target_yaw - current_yaw), math.cos(target_yaw - current_yaw))
    return float(np.clip(gain * e, -max_rate, max_rate))


