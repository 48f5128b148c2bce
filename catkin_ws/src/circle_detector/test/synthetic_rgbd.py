"""A small synthetic RGB-D renderer of a facade fire holder for tests, benchmarks and the publisher.

The facade is a textured plane seen by the RealSense colour camera (640x480, fx = fy = 462.1) from a
given distance and angle; on it, a row of three dark discs (0.15 m radius, 0.7 m apart, as in the C3 world): the real hole in the middle (the depth looks
through it to the container behind) and a painted decoy on each side (flat). Colour gets shading and
noise, depth gets distance-dependent noise, dropouts and millimetre quantisation; beyond the facade is
sky (no depth).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Tuple

import numpy as np

from circle_detector.hough import Intrinsics

DEFAULT_K = Intrinsics(462.1, 462.1, 320.0, 240.0, 640, 480)
HOLE_DEPTH = 0.3          # container behind the hole (m)
FACADE_HALF_WIDTH = 4.0   # extent of the facade around the holder (m)
FACADE_HALF_HEIGHT = 2.5


@dataclass(frozen=True)
class FacadeScene:
    """The holder seen from the camera.

    Args:
        hole_cam: optical-frame position (x right, y down, z forward) of the hole centre (m).
        yaw, pitch: rotation of the facade about the camera's vertical / horizontal axis (rad).
        radius: radius of the hole and of the decoys (m).
        spacing: distance between neighbouring circle centres (m).
        wall_grey, disc_grey: brightness of the wall and of the discs (0-255).
    """

    hole_cam: Tuple[float, float, float]
    yaw: float
    pitch: float
    radius: float
    spacing: float
    wall_grey: float
    disc_grey: float

    def axes(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Facade horizontal axis, vertical (down) axis and normal (away from the camera)."""
        cy, sy, cp, sp = math.cos(self.yaw), math.sin(self.yaw), math.cos(self.pitch), math.sin(self.pitch)
        ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
        rx = np.array([[1, 0, 0], [0, cp, -sp], [0, sp, cp]])
        r = ry @ rx
        return r[:, 0], r[:, 1], r[:, 2]

    def circle_centres(self) -> np.ndarray:
        """Optical-frame centres of (left decoy, hole, right decoy), shape (3, 3)."""
        e_h, _, _ = self.axes()
        c = np.asarray(self.hole_cam)
        return np.stack([c - self.spacing * e_h, c, c + self.spacing * e_h])

    def project(self, p: np.ndarray, K: Intrinsics = DEFAULT_K) -> Tuple[float, float]:
        """Pixel of an optical-frame point."""
        return K.cx + K.fx * p[0] / p[2], K.cy + K.fy * p[1] / p[2]


def random_scene(rng: np.random.Generator, distance: float, max_angle_deg: float = 40.0,
                 K: Intrinsics = DEFAULT_K) -> FacadeScene:
    """The holder at `distance` m (to the hole), facade turned up to `max_angle_deg`, all three in view."""
    yaw = math.radians(rng.uniform(-max_angle_deg, max_angle_deg))
    pitch = math.radians(rng.uniform(-5.0, 5.0))
    radius = rng.uniform(0.12, 0.18)   # C3 world / ual_sim: 0.15 m hole and decoys, 0.7 m apart
    spacing = rng.uniform(0.6, 0.8)
    for _ in range(100):  # keep the three circles inside the image
        bx, by = rng.uniform(-0.25, 0.25) * distance, rng.uniform(-0.25, 0.25) * distance
        z = math.sqrt(max(distance ** 2 - bx ** 2 - by ** 2, 0.25))
        s = FacadeScene((bx, by, z), yaw, pitch, radius, spacing, 0, 0)
        ok = True
        for c in s.circle_centres():
            u, v = s.project(c, K)
            m = K.fx * radius * 1.4 / c[2]
            ok &= c[2] > 0.3 and m < u < K.width - m and m < v < K.height - m
        if ok:
            break
    else:
        bx, by, z = 0.0, 0.0, distance
    wall = rng.uniform(110, 210)
    return FacadeScene((bx, by, z), yaw, pitch, radius, spacing, wall, rng.uniform(10, max(20.0, wall - 70)))


def render(scene: FacadeScene, rng: np.random.Generator, K: Intrinsics = DEFAULT_K,
           noise_std: float = 6.0, depth_dropout: float = 0.03) -> Tuple[np.ndarray, np.ndarray]:
    """(colour bgr8 HxWx3, depth 16UC1 mm HxW) of the scene."""
    h, w = K.height, K.width
    uu, vv = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    rays = np.stack([(uu - K.cx) / K.fx, (vv - K.cy) / K.fy, np.ones_like(uu)], axis=-1)
    e_h, e_v, n = scene.axes()
    c0 = np.asarray(scene.hole_cam)
    denom = rays @ n
    t = np.where(denom > 1e-6, (c0 @ n) / np.maximum(denom, 1e-6), np.inf)
    hit = rays * t[..., None]
    rel = hit - c0
    a, b = rel @ e_h, rel @ e_v
    on_facade = np.isfinite(t) & (np.abs(a) < FACADE_HALF_WIDTH) & (np.abs(b) < FACADE_HALF_HEIGHT)
    px_m = hit[..., 2] / K.fx  # metres per pixel on the facade, for anti-aliased edges
    # wall: shading, a coarse brick texture and the discs
    grey = scene.wall_grey * (0.85 + 0.15 * np.cos(0.7 * a + 0.4 * b))
    grey = grey + 6.0 * np.sign(np.sin(a * 2 * math.pi / 0.4)) * np.sign(np.sin(b * 2 * math.pi / 0.2))
    in_hole = np.zeros_like(t, dtype=bool)
    for k, offset in enumerate((-scene.spacing, 0.0, scene.spacing) if scene.radius > 0 else ()):
        dist = np.hypot(a - offset, b)
        alpha = np.clip(0.5 - (dist - scene.radius) / np.maximum(px_m, 1e-6), 0.0, 1.0)
        grey = grey * (1 - alpha) + scene.disc_grey * alpha
        if k == 1:
            in_hole = dist < scene.radius
    colour = np.stack([grey * 0.95, grey, grey * 1.05], axis=-1)
    colour[~on_facade] = (235, 206, 135)  # sky (bgr)
    colour = colour + rng.normal(0.0, noise_std, colour.shape)
    colour = np.clip(colour, 0, 255).astype(np.uint8)
    z = hit[..., 2].copy()
    # through the hole: the container HOLE_DEPTH behind the facade
    t_back = np.where(denom > 1e-6, (c0 @ n + HOLE_DEPTH) / np.maximum(denom, 1e-6), np.inf)
    z = np.where(in_hole, rays[..., 2] * t_back, z)
    z = z + rng.normal(0.0, 1.0, z.shape) * (0.002 + 0.002 * z ** 2)
    depth = np.where(on_facade & (z > 0.2) & (z < 10.0), np.round(z * 1000.0), 0)
    depth[rng.random(depth.shape) < depth_dropout] = 0
    return colour, depth.astype(np.uint16)


# Named scenes for the synthetic publisher, the rostests and the recordings.
NAMED_SCENES = {
    # holder 3 m ahead, slightly left and below, facade turned 20 degrees
    "facade_holder": FacadeScene((-0.2, 0.1, 3.0), math.radians(20.0), math.radians(-3.0), 0.15, 0.7, 170.0, 40.0),
    # the same facade with no holder: nothing round to find
    "plain_wall": FacadeScene((-0.2, 0.1, 3.0), math.radians(20.0), math.radians(-3.0), 0.0, 0.7, 170.0, 40.0),
}
