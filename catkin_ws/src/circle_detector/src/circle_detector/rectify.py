"""Fronto-parallel rectification of a facade from the depth image.

Seen 40 degrees off its normal, a round hole is an ellipse 0.77 as wide as it is tall and HoughCircles
misses it. The depth image gives the facade plane; rotating the camera virtually (a homography
K R K^-1 about the optical centre) to face that plane turns every circle on it back into a circle, with
one metres-per-pixel scale over the whole view.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Tuple

import cv2
import numpy as np

PLANE_SAMPLE_STEP = 8        # pixels between depth samples of the plane fit
PLANE_MIN_POINTS = 200
PLANE_INLIER_M = 0.05        # residual of a facade point (m)
PLANE_MIN_INLIER_FRACTION = 0.5
MIN_TILT_RAD = np.radians(8.0)   # below this tilt the original image is used as it is
MAX_CANVAS_GROWTH = 1.6      # the rectified canvas is at most this much larger per side


@dataclass(frozen=True)
class Plane:
    """Plane n . p = d in the optical frame, n unit and pointing away from the camera (n_z > 0)."""

    normal: np.ndarray
    d: float


@dataclass(frozen=True)
class Rectification:
    """The homography from original to rectified pixels, its inverse and the pixel scale (px per m at d)."""

    H: np.ndarray
    H_inv: np.ndarray
    size: Tuple[int, int]          # (width, height) of the rectified image
    px_per_m: float                # pixels of the rectified image per metre on the plane


def fit_plane(depth_m: np.ndarray, fx: float, fy: float, cx: float, cy: float,
              rng: Optional[np.random.Generator] = None, iterations: int = 30) -> Optional[Plane]:
    """Dominant plane of the depth image (RANSAC on a sparse grid, then least squares on the inliers)."""
    sub = depth_m[::PLANE_SAMPLE_STEP, ::PLANE_SAMPLE_STEP]
    vv, uu = np.mgrid[0:depth_m.shape[0]:PLANE_SAMPLE_STEP, 0:depth_m.shape[1]:PLANE_SAMPLE_STEP]
    ok = np.isfinite(sub)
    if ok.sum() < PLANE_MIN_POINTS:
        return None
    z = sub[ok]
    pts = np.stack([(uu[ok] - cx) * z / fx, (vv[ok] - cy) * z / fy, z], axis=1)
    rng = rng or np.random.default_rng(0)
    # every RANSAC hypothesis at once: (iterations, 3) normals from random point triples
    tri = pts[rng.integers(0, len(pts), size=(iterations, 3))]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norms = np.linalg.norm(normals, axis=1)
    good = norms > 1e-9
    if not good.any():
        return None
    normals, anchors = normals[good] / norms[good, None], tri[good, 0]
    offsets = np.einsum("ij,ij->i", normals, anchors)
    counts = (np.abs(pts @ normals.T - offsets) < PLANE_INLIER_M).sum(axis=0)
    k = int(np.argmax(counts))
    if counts[k] < PLANE_MIN_INLIER_FRACTION * len(pts):
        return None
    best = (normals[k], anchors[k])
    inl = pts[np.abs((pts - best[1]) @ best[0]) < PLANE_INLIER_M]
    centre = inl.mean(axis=0)
    _, _, vt = np.linalg.svd(inl - centre, full_matrices=False)
    n = vt[2]
    if n[2] < 0:
        n = -n
    return Plane(n, float(n @ centre))


def rectification(plane: Plane, fx: float, fy: float, cx: float, cy: float, width: int,
                  height: int) -> Optional[Rectification]:
    """Homography to a virtual camera facing the plane, with the image re-centred on the warped view.

    Returns None when the plane is nearly fronto-parallel already (no need) or seen too obliquely.
    """
    n = plane.normal
    tilt = np.arccos(np.clip(n[2], -1.0, 1.0))
    if tilt < MIN_TILT_RAD or tilt > np.radians(70.0):
        return None
    y_axis = np.array([0.0, 1.0, 0.0]) - n[1] * n
    y_axis /= np.linalg.norm(y_axis)
    x_axis = np.cross(y_axis, n)
    R = np.stack([x_axis, y_axis, n])  # rows: virtual camera axes in the original optical frame
    K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    H = K @ R @ np.linalg.inv(K)
    corners = np.array([[0, 0], [width, 0], [0, height], [width, height]], dtype=np.float64).reshape(-1, 1, 2)
    warped = cv2.perspectiveTransform(corners, H).reshape(-1, 2)
    lo, hi = warped.min(axis=0), warped.max(axis=0)
    span = hi - lo
    scale = min(1.0, MAX_CANVAS_GROWTH * width / span[0], MAX_CANVAS_GROWTH * height / span[1])
    # keep the centre of the warped view in the middle of the canvas
    w_out, h_out = int(np.ceil(span[0] * scale)), int(np.ceil(span[1] * scale))
    S = np.array([[scale, 0, -lo[0] * scale], [0, scale, -lo[1] * scale], [0, 0, 1.0]])
    Hs = S @ H
    return Rectification(Hs, np.linalg.inv(Hs), (w_out, h_out), fx * scale / plane.d)


def to_original(rect: Rectification, u: float, v: float) -> Tuple[float, float]:
    """Pixel of the original image for a pixel of the rectified one."""
    p = rect.H_inv @ np.array([u, v, 1.0])
    return float(p[0] / p[2]), float(p[1] / p[2])


def intersect(plane: Plane, u: float, v: float, fx: float, fy: float, cx: float, cy: float) -> Optional[np.ndarray]:
    """Optical-frame point of the plane seen at pixel (u, v)."""
    ray = np.array([(u - cx) / fx, (v - cy) / fy, 1.0])
    den = ray @ plane.normal
    if den <= 1e-6:
        return None
    return ray * (plane.d / den)
