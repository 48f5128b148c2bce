"""A small synthetic thermal world for tests, benchmarks and the synthetic publisher.

It renders what the 32x32 camera sees of one flat surface (a facade ahead for FORWARD, the ground below
for DOWNWARD) holding at most one round heat source, plus the front laser window, with sensor noise,
glitching hot pixels, NaN/inf laser beams and a sun-heated wall case. Each pixel averages 3x3 rays, so a
far, small fire blends with the wall the way a real low-resolution bolometer blurs it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import List, Optional, Tuple

import numpy as np

from fire_detector import constants as C

SCENE_KINDS = ("fire", "empty", "inactive_holder", "hot_wall")
SUPERSAMPLE = 3
LASER_BEAMS = 720
LASER_RANGE_MAX = 25.0
LASER_RANGE_MIN = 0.15
AMBIENT = 30.0
ATTEN_DIST = 6.0
# The C3 world's heat sources (docs/c3_world.md; same figures as ual_sim's model): facade holder = ring of
# flames (0.4 m, 250 degC) around the hole with a heater (0.15 m, 120 degC), both cooling as the fire is
# filled with water; ground fire = plate of 0.5 m at 120 degC (45 under a blanket); inactive holder 28;
# sun-heated facades and roofs 40-45; interior walls 31; ground 34.
RING_RADIUS, HOLE_RADIUS, PLATE_RADIUS = 0.4, 0.15, 0.5


@dataclass(frozen=True)
class ThermalScene:
    """One viewpoint of one heat source.

    Args:
        direction: C.CAMERA_DIRECTION_FORWARD or C.CAMERA_DIRECTION_DOWNWARD.
        distance: metres from the UAV to the surface along the camera axis (FORWARD: wall, DOWNWARD: height).
        angle: rotation of the surface about the vertical (FORWARD) or tilt (DOWNWARD) in radians.
        source_offset: (lateral, vertical) position of the source on the surface, metres from the point the
            camera axis hits (lateral: to the UAV's left; vertical: up, or forward for DOWNWARD).
        source_radius: radius of the heat source (m); 0 for none.
        source_temp, surface_temp: degrees C (true temperatures; the camera sees their contrast to the
            30 degC ambient fade with distance as 1 / (1 + (d / 6 m)^2), as in ual_sim).
        inner_radius, inner_temp: a hotter or colder disc in the middle (the heater in the hole).
        uav_xyz, uav_yaw: pose of the UAV in the arena frame.
        kind: one of SCENE_KINDS (what the benchmark counts as truth: only "fire" is a fire).
    """

    direction: int
    distance: float
    angle: float
    source_offset: Tuple[float, float]
    source_radius: float
    source_temp: float
    surface_temp: float
    uav_xyz: Tuple[float, float, float]
    uav_yaw: float
    kind: str = "fire"
    inner_radius: float = 0.0
    inner_temp: float = 0.0

    def _axes(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Surface point on the camera axis, its normal (away from the UAV) and in-plane axes (body frame)."""
        ca, sa = math.cos(self.angle), math.sin(self.angle)
        if self.direction == C.CAMERA_DIRECTION_FORWARD:
            p0 = np.array([self.distance, 0.0, 0.0])
            n = np.array([ca, sa, 0.0])
            e_lat = np.array([-sa, ca, 0.0])
            e_vert = np.array([0.0, 0.0, 1.0])
        else:
            p0 = np.array([0.0, 0.0, -self.distance])
            n = np.array([sa, 0.0, -ca])
            e_lat = np.array([0.0, 1.0, 0.0])
            e_vert = np.array([ca, 0.0, sa])
        return p0, n, e_lat, e_vert

    def source_body(self) -> np.ndarray:
        """Body-frame position of the heat source centre."""
        p0, _, e_lat, e_vert = self._axes()
        return p0 + self.source_offset[0] * e_lat + self.source_offset[1] * e_vert

    def source_arena(self) -> Tuple[float, float, float]:
        """Arena-frame position of the heat source centre (the truth the detector is scored against)."""
        b = self.source_body()
        c, s = math.cos(self.uav_yaw), math.sin(self.uav_yaw)
        x, y, z = self.uav_xyz
        return (x + c * b[0] - s * b[1], y + s * b[0] + c * b[1], z + b[2])

    def source_in_view(self, margin_px: float = 0.0) -> bool:
        """True when the source centre projects inside the image (minus a margin)."""
        b = self.source_body()
        if self.direction == C.CAMERA_DIRECTION_FORWARD:
            depth, col, row = b[0], -b[1], -b[2]
        else:
            depth, col, row = -b[2], -b[1], -b[0]
        if depth <= 0:
            return False
        u = C.CENTER_U + C.FOCAL_PX * col / depth
        v = C.CENTER_V + C.FOCAL_PX * row / depth
        lo, hi = -0.5 + margin_px, C.IMG_WIDTH - 0.5 - margin_px
        return lo <= u <= hi and lo <= v <= hi


def _pixel_rays(direction: int) -> np.ndarray:
    """Body-frame ray directions of every sub-sample, shape (32*S, 32*S, 3)."""
    n = C.IMG_WIDTH * SUPERSAMPLE
    sub = (np.arange(n) + 0.5) / SUPERSAMPLE - 0.5  # pixel coordinates of the sub-samples
    uu, vv = np.meshgrid(sub, sub)
    a = (uu - C.CENTER_U) / C.FOCAL_PX  # right
    b = (vv - C.CENTER_V) / C.FOCAL_PX  # down in the image
    one = np.ones_like(a)
    if direction == C.CAMERA_DIRECTION_FORWARD:
        return np.stack([one, -a, -b], axis=-1)
    # DOWNWARD: looks along -z, image top = UAV front, image right = UAV right.
    return np.stack([-b, -a, -one], axis=-1)


_RAYS = {d: _pixel_rays(d) for d in (C.CAMERA_DIRECTION_FORWARD, C.CAMERA_DIRECTION_DOWNWARD)}


def render_frame(scene: ThermalScene, rng: np.random.Generator, noise_std: float = 0.4,
                 glitch_prob: float = 0.3) -> np.ndarray:
    """Temperatures (deg C) seen by the camera, 32x32, with noise and, sometimes, glitching hot pixels."""
    rays = _RAYS[scene.direction]
    p0, n, e_lat, e_vert = scene._axes()
    denom = rays @ n
    t = np.where(denom > 1e-6, (p0 @ n) / np.maximum(denom, 1e-6), np.inf)
    hit = rays * t[..., None]
    rel = hit - scene.source_body()
    d_lat, d_vert = rel @ e_lat, rel @ e_vert
    temp = np.full(t.shape, scene.surface_temp)
    # a mild gradient over the surface (sunlight, materials), up to about 1.5 degC across the view
    temp = temp + 1.5 * np.tanh(0.1 * (hit @ e_vert))
    if scene.source_radius > 0:
        r2 = d_lat ** 2 + d_vert ** 2
        temp = np.where(np.isfinite(t) & (r2 <= scene.source_radius ** 2), scene.source_temp, temp)
        if scene.inner_radius > 0:
            temp = np.where(np.isfinite(t) & (r2 <= scene.inner_radius ** 2), scene.inner_temp, temp)
    dist = np.where(np.isfinite(t), t * np.linalg.norm(rays, axis=-1), 0.0)
    temp = AMBIENT + (temp - AMBIENT) / (1.0 + (dist / ATTEN_DIST) ** 2)
    temp = np.where(np.isfinite(t), temp, 20.0)  # sky
    s = SUPERSAMPLE
    frame = temp.reshape(C.IMG_HEIGHT, s, C.IMG_WIDTH, s).mean(axis=(1, 3))
    frame = frame + rng.normal(0.0, noise_std, frame.shape)
    if rng.random() < glitch_prob:  # a few pixels of a passing warm object / sensor glitch
        k = int(rng.integers(1, 4))
        rr, cc = rng.integers(0, C.IMG_HEIGHT, k), rng.integers(0, C.IMG_WIDTH, k)
        frame[rr, cc] = rng.uniform(40.0, 90.0, k)
    return frame


def render_scan(scene: ThermalScene, rng: np.random.Generator, noise_std: float = 0.02,
                dropout: float = 0.1) -> Tuple[np.ndarray, float, float]:
    """A 720-beam LaserScan (ranges, angle_min, angle_increment) of the FORWARD surface, front at 360.

    Beams that miss the wall read +inf; a fraction `dropout` of the front beams is NaN or inf.
    """
    inc = 2 * math.pi / LASER_BEAMS
    angles = -math.pi + inc * np.arange(LASER_BEAMS)
    ranges = np.full(LASER_BEAMS, np.inf)
    if scene.direction == C.CAMERA_DIRECTION_FORWARD:
        p0, n, _, _ = scene._axes()
        denom = np.cos(angles) * n[0] + np.sin(angles) * n[1]
        ok = denom > 1e-3
        ranges[ok] = (p0 @ n) / denom[ok]
        ranges[ranges > LASER_RANGE_MAX] = np.inf
        ranges = ranges + rng.normal(0.0, noise_std, LASER_BEAMS)
        front = slice(LASER_BEAMS // 2 - 30, LASER_BEAMS // 2 + 31)
        bad = rng.random(61) < dropout
        vals = ranges[front].copy()
        vals[bad] = rng.choice([np.nan, np.inf, 0.0], size=int(bad.sum()))
        ranges[front] = vals
    return ranges, -math.pi, inc


def random_scene(rng: np.random.Generator, direction: int, distance: float, kind: str,
                 max_angle_deg: float = 40.0, sun_range: Tuple[float, float] = (40.0, 45.0)) -> ThermalScene:
    """A random viewpoint at `distance` metres of one of SCENE_KINDS.

    fire: an active holder (FORWARD, partly cooled by water: 30-100 % of its heat) on a sun-heated or
    interior wall, or a ground plate (DOWNWARD); empty: a cool surface; inactive_holder: a cold holder on
    a sun-heated wall (FORWARD) or a plate under a blanket (DOWNWARD); hot_wall: a sun-heated facade or
    roof with nothing on it. Sources are placed within 12 degrees of the camera axis. `sun_range`: the
    temperature of sun-heated surfaces (desert walls in full sun: 50-55 degC).
    """
    if kind not in SCENE_KINDS:
        raise ValueError(f"unknown scene kind {kind!r}")
    forward = direction == C.CAMERA_DIRECTION_FORWARD
    angle = math.radians(rng.uniform(-max_angle_deg, max_angle_deg) if forward else rng.uniform(-5.0, 5.0))
    bearing = math.radians(12.0)
    off = (rng.uniform(-1, 1) * distance * math.tan(bearing), rng.uniform(-1, 1) * distance * math.tan(bearing))
    sun = rng.uniform(*sun_range)
    surface = (sun if rng.random() < 0.7 else 31.0) if forward else 34.0
    radius, hot, inner_r, inner_t = 0.0, 0.0, 0.0, 0.0
    if kind == "fire":
        if forward:
            heat = rng.uniform(0.3, 1.0)
            radius, hot = RING_RADIUS, surface + (250.0 - surface) * heat
            inner_r, inner_t = HOLE_RADIUS, surface + (120.0 - surface) * heat
        else:
            radius, hot = PLATE_RADIUS, 120.0
    elif kind == "empty":
        surface = 31.0 if forward else 34.0
    elif kind == "inactive_holder":
        radius, hot = (RING_RADIUS, 28.0) if forward else (PLATE_RADIUS, 45.0)
        surface = sun if forward else 34.0
    elif kind == "hot_wall":
        surface = sun
    uav = (rng.uniform(-5, 30), rng.uniform(-5, 30), rng.uniform(1.0, 15.0))
    if not forward:
        uav = (uav[0], uav[1], distance)
    return ThermalScene(direction, distance, angle, off, radius, hot, surface, uav,
                        rng.uniform(-math.pi, math.pi), kind, inner_r, inner_t)


def jitter(scene: ThermalScene, rng: np.random.Generator, pos_std: float = 0.03,
           yaw_std: float = 0.01) -> ThermalScene:
    """The same scene a frame later: the hovering UAV sways a little (the source stays put)."""
    dx, dy = rng.normal(0.0, pos_std, 2)
    return replace(scene, source_offset=(scene.source_offset[0] + dx, scene.source_offset[1] + dy))


def sequence(scene: ThermalScene, rng: np.random.Generator, n_frames: int) -> List[Tuple[ThermalScene, np.ndarray]]:
    """`n_frames` consecutive (scene, frame) pairs of a hovering UAV."""
    out = []
    s = scene
    for _ in range(n_frames):
        s = jitter(scene, rng)
        out.append((s, render_frame(s, rng)))
    return out


def scene_truth(scene: ThermalScene) -> Optional[Tuple[float, float, float]]:
    """Arena position of the fire if the scene holds a visible fire, else None."""
    if scene.kind == "fire" and scene.source_in_view():
        return scene.source_arena()
    return None


# Named scenes of the C3 world (docs/c3_world.md), used by the synthetic publisher, the rostests and the
# recordings: the UAV hovers in front of / above a known fire holder.
NAMED_SCENES = {
    # facade A (y = 19.5), holder (17.4, 19.5, 10.5), active; UAV 3 m in front, facing +y
    "facade_fire": ThermalScene(C.CAMERA_DIRECTION_FORWARD, 3.0, math.radians(10.0), (0.0, 0.0), RING_RADIUS,
                                250.0, 42.0, (17.4, 16.5, 10.5), math.pi / 2, "fire", HOLE_RADIUS, 120.0),
    # facade A, holder (12.4, 19.5, 6.5), inactive (cold); UAV 2.5 m in front
    "inactive_holder": ThermalScene(C.CAMERA_DIRECTION_FORWARD, 2.5, 0.0, (0.0, 0.0), RING_RADIUS, 28.0,
                                    42.0, (12.4, 17.0, 6.5), math.pi / 2, "inactive_holder"),
    # facade D (x = 24.2) heated by the sun to 43 degC, no fire; UAV 3 m away facing +x
    "hot_wall": ThermalScene(C.CAMERA_DIRECTION_FORWARD, 3.0, math.radians(-15.0), (0.0, 0.0), 0.0, 0.0,
                             43.0, (21.2, 12.7, 10.5), 0.0, "hot_wall"),
    # outdoor holder (1, 14, 0) seen from 4 m above, slightly off-centre
    "ground_fire": ThermalScene(C.CAMERA_DIRECTION_DOWNWARD, 4.0, 0.0, (0.3, 0.2), PLATE_RADIUS, 120.0,
                                34.0, (1.2, 13.7, 4.0), math.radians(30.0), "fire"),
}


def colour_map(frame: np.ndarray) -> np.ndarray:
    """The rgb_image of the camera: the frame on a relative (min..max) scale, rgb8 32x32x3."""
    import cv2

    f = np.nan_to_num(frame, nan=float(np.nanmin(frame)))
    lo, hi = float(f.min()), float(f.max())
    g = ((f - lo) / max(hi - lo, 1e-6) * 255).astype(np.uint8)
    return cv2.cvtColor(cv2.applyColorMap(g, cv2.COLORMAP_JET), cv2.COLOR_BGR2RGB)
