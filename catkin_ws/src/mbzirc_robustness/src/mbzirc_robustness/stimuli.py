"""Valid inputs too big for a probe's YAML: a synthetic RGB-D view of a facade fire holder.

Why: the circle detector's function (synchronised colour + depth in, the middle hole out) can only be
checked with a real image pair. This renders one, once, with numpy: a RealSense-like camera (640x480,
fx = fy = 462.1) 3 m square in front of a wall with three dark discs 0.15 m in radius, 0.7 m apart (the
size of the C3 holders a team knew before the trial); the depth looks 0.3 m deeper through the middle one
(the real hole) and is flat on the two painted decoys. No noise: a probe must not fail by chance.
"""
from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

WIDTH, HEIGHT = 640, 480
FX = FY = 462.1
CX, CY = 320.0, 240.0
WALL_DISTANCE_M = 3.0
DISC_RADIUS_M = 0.15
DISC_SPACING_M = 0.7
HOLE_DEPTH_M = 0.3          # the container behind the real hole
WALL_GREY, DISC_GREY = 170.0, 35.0

# topics of a RealSense namespace (as the circle detector and the simulator name them)
COLOR_TOPIC = "color/image_rect_color"
DEPTH_TOPIC = "aligned_depth_to_color/image_raw"
INFO_TOPIC = "color/camera_info"


@lru_cache(maxsize=1)
def facade_holder_arrays() -> tuple[np.ndarray, np.ndarray]:
    """(bgr8 HxWx3 uint8, depth 16UC1 HxW uint16 mm) of the holder; the hole is at the optical centre."""
    uu, vv = np.meshgrid(np.arange(WIDTH, dtype=np.float64), np.arange(HEIGHT, dtype=np.float64))
    a = (uu - CX) / FX * WALL_DISTANCE_M          # metres on the wall, right of the hole
    b = (vv - CY) / FY * WALL_DISTANCE_M          # metres on the wall, below it
    px_m = WALL_DISTANCE_M / FX                   # metres per pixel, for anti-aliased rims
    grey = np.full(a.shape, WALL_GREY)
    for offset in (-DISC_SPACING_M, 0.0, DISC_SPACING_M):
        alpha = np.clip(0.5 - (np.hypot(a - offset, b) - DISC_RADIUS_M) / px_m, 0.0, 1.0)
        grey = grey * (1.0 - alpha) + DISC_GREY * alpha
    colour = np.clip(np.stack([grey, grey, grey], axis=-1), 0, 255).astype(np.uint8)
    depth = np.full(a.shape, WALL_DISTANCE_M * 1000.0)
    depth[np.hypot(a, b) < DISC_RADIUS_M] = (WALL_DISTANCE_M + HOLE_DEPTH_M) * 1000.0
    return colour, depth.astype(np.uint16)


def facade_holder_messages(camera_ns: str, frame_id: str, stamp: Any) -> list[list[tuple[str, Any]]]:
    """The stimulus as groups of (topic, message), to be sent group after group: camera_info first (the
    detector drops images until it has one), then colour and depth with the same stamp (its synchroniser
    pairs them by stamp)."""
    from sensor_msgs.msg import CameraInfo, Image
    colour, depth = facade_holder_arrays()
    ns = camera_ns.rstrip("/")
    info = CameraInfo(height=HEIGHT, width=WIDTH, distortion_model="plumb_bob", D=[0.0] * 5,
                      K=[FX, 0.0, CX, 0.0, FY, CY, 0.0, 0.0, 1.0], R=[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0],
                      P=[FX, 0.0, CX, 0.0, 0.0, FY, CY, 0.0, 0.0, 0.0, 1.0, 0.0])
    c = Image(height=HEIGHT, width=WIDTH, encoding="bgr8", is_bigendian=0, step=WIDTH * 3, data=colour.tobytes())
    d = Image(height=HEIGHT, width=WIDTH, encoding="16UC1", is_bigendian=0, step=WIDTH * 2, data=depth.tobytes())
    for m in (info, c, d):
        m.header.stamp, m.header.frame_id = stamp, frame_id
    return [[(f"{ns}/{INFO_TOPIC}", info)], [(f"{ns}/{COLOR_TOPIC}", c), (f"{ns}/{DEPTH_TOPIC}", d)]]
