"""The Hough pipeline on one colour + depth pair: depth mask, optional blur, HoughCircles, metric filter."""
from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional, Tuple

import cv2
import numpy as np

from circle_detector import constants as C
from circle_detector.rectify import fit_plane, intersect, rectification, to_original

# No OpenCV worker threads: a frame takes a few ms, and the robot's computer is shared by many nodes, so
# threads cost more CPU than they save (bench_detectors measures the pipeline this way, as the node runs).
cv2.setNumThreads(1)


@dataclass
class HoughParams:
    """The original node's parameters (pixel values at full resolution) plus `downscale`."""

    dp: float = C.DEFAULT_DP
    min_dist_between_circle_center: float = C.DEFAULT_MIN_DIST_BETWEEN_CIRCLE_CENTER
    canny_edge_upper_threshold: float = C.DEFAULT_CANNY_EDGE_UPPER_THRESHOLD
    accumulator_threshold: float = C.DEFAULT_ACCUMULATOR_THRESHOLD
    min_radius: int = C.DEFAULT_MIN_RADIUS
    max_radius: int = C.DEFAULT_MAX_RADIUS
    min_radius_meters: float = C.DEFAULT_MIN_RADIUS_METERS
    max_radius_meters: float = C.DEFAULT_MAX_RADIUS_METERS
    max_depth_th: float = C.DEFAULT_MAX_DEPTH_TH
    use_gaussian_blur: bool = C.DEFAULT_USE_GAUSSIAN_BLUR
    gaussian_blur_sigma: float = C.DEFAULT_GAUSSIAN_BLUR_SIGMA
    gaussian_blur_kernel_size: int = C.DEFAULT_GAUSSIAN_BLUR_KERNEL_SIZE
    downscale: int = C.DEFAULT_DOWNSCALE
    rectify: bool = C.DEFAULT_RECTIFY


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole model of the colour camera (the depth is aligned to it)."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    @classmethod
    def from_k(cls, k, width: int, height: int) -> "Intrinsics":
        """From the 9 values of CameraInfo.K; raises ValueError on a degenerate matrix."""
        if len(k) != 9 or not (k[0] > 0 and k[4] > 0) or not np.all(np.isfinite(k)):
            raise ValueError("camera_info K is degenerate")
        return cls(float(k[0]), float(k[4]), float(k[2]), float(k[5]), int(width), int(height))


@dataclass(frozen=True)
class Circle:
    """A detected circle: image centre and radius (px, full resolution) and its 3D centre and radius (m).

    x, y, z are in the optical frame of the colour camera (x right, y down, z forward).
    """

    u: float
    v: float
    radius_px: float
    x: float
    y: float
    z: float
    radius_m: float
    # extension: how far (m, along the optical axis) the middle of the disc lies behind its rim: about
    # the container depth for a real hole, about 0 for a painted decoy; NaN when the depth has no data
    opening_m: float = float("nan")


def depth_to_metres(depth: np.ndarray, encoding: str) -> np.ndarray:
    """Depth image as float32 metres with NaN for no data; accepts 16UC1 (mm) and 32FC1 (m)."""
    if encoding in ("16UC1", "mono16"):
        d = depth.astype(np.float32) * C.DEPTH_SCALE_16UC1
        d[depth == 0] = np.nan
        return d
    if encoding == "32FC1":
        d = depth.astype(np.float32, copy=True)
        d[~np.isfinite(d) | (d <= 0)] = np.nan
        return d
    raise ValueError(f"unsupported depth encoding {encoding!r} (expected 16UC1 or 32FC1)")


def _annulus_depth(depth_m: np.ndarray, u: float, v: float, r_in: float, r_out: float,
                   min_valid: int) -> Optional[float]:
    """Median valid depth of the pixels between r_in and r_out (px) around (u, v), or None."""
    h, w = depth_m.shape
    x0, x1 = max(0, int(u - r_out)), min(w, int(u + r_out) + 1)
    y0, y1 = max(0, int(v - r_out)), min(h, int(v + r_out) + 1)
    if x0 >= x1 or y0 >= y1:
        return None
    patch = depth_m[y0:y1, x0:x1]
    yy, xx = np.mgrid[y0:y1, x0:x1]
    d2 = (xx - u) ** 2 + (yy - v) ** 2
    vals = patch[(d2 >= r_in ** 2) & (d2 <= r_out ** 2)]
    vals = vals[np.isfinite(vals)]
    if vals.size < min_valid:
        return None
    return float(np.median(vals))


def _rim_depth(depth_m: np.ndarray, u: float, v: float, r: float) -> Optional[float]:
    """Median valid depth of the annulus just outside the circle (the facade around the hole)."""
    return _annulus_depth(depth_m, u, v, r * C.RIM_INNER, r * C.RIM_OUTER, C.RIM_MIN_VALID)


def _inside_depth(depth_m: np.ndarray, u: float, v: float, r: float) -> float:
    """Median depth of the middle of the disc (NaN when unknown): behind the rim for a real opening."""
    d = _annulus_depth(depth_m, u, v, 0.0, max(1.0, r * C.INSIDE_RADIUS), C.INSIDE_MIN_VALID)
    return float("nan") if d is None else d


def _radius_bounds(p: HoughParams, px_per_m_near: float, px_per_m_far: float, s: int) -> Tuple[int, int]:
    """Hough radius bounds (px of the working image): the params, or, where 0, the metric bounds seen
    at the nearest / farthest valid depth (an extension: unbounded Hough is slow and finds huge circles)."""
    lo = p.min_radius / s if p.min_radius > 0 else p.min_radius_meters * px_per_m_far / s
    hi = p.max_radius / s if p.max_radius > 0 else p.max_radius_meters * px_per_m_near / s
    return max(1, int(np.floor(lo))), max(2, int(np.ceil(hi)))


def detect_circles(color_bgr: np.ndarray, depth_m: np.ndarray, K: Intrinsics, p: HoughParams,
                   debug: Optional[dict] = None) -> List[Circle]:
    """Circles of plausible metric size in one colour + depth pair.

    Steps: grey image masked to the pixels with valid depth under `max_depth_th` (the sky and far
    background go black); if `rectify`, the facade plane is fitted to the depth and the image warped to
    face it (circles seen at an angle become circles again); shrunk by `downscale` (pixel parameters
    follow); optional Gaussian blur; HoughCircles (gradient method); then the 3D centre (on the fitted
    plane, or from the depth of the circle's rim) and the radius in metres, kept within
    [min_radius_meters, max_radius_meters]. Raises ValueError if the images do not match each other.
    """
    if color_bgr.ndim != 3 or color_bgr.shape[2] != 3:
        raise ValueError(f"colour image must be HxWx3, got shape {color_bgr.shape}")
    if depth_m.shape != color_bgr.shape[:2]:
        raise ValueError(f"depth {depth_m.shape[1]}x{depth_m.shape[0]} and colour "
                         f"{color_bgr.shape[1]}x{color_bgr.shape[0]} differ in size")
    s = max(1, int(p.downscale))
    h, w = depth_m.shape
    with np.errstate(invalid="ignore"):
        valid = depth_m < p.max_depth_th  # NaN compares False
    zs = depth_m[::8, ::8]
    zs = zs[np.isfinite(zs) & (zs < p.max_depth_th)]
    if zs.size == 0:
        return []
    z_near, z_far = float(np.percentile(zs, 1)), float(np.percentile(zs, 99))
    gray = cv2.cvtColor(color_bgr, cv2.COLOR_BGR2GRAY)
    gray = cv2.multiply(gray, valid.view(np.uint8))  # mask: no or far depth -> black
    plane = rect = None
    if p.rectify:
        plane = fit_plane(np.where(valid, depth_m, np.nan), K.fx, K.fy, K.cx, K.cy)
        if plane is not None:
            rect = rectification(plane, K.fx, K.fy, K.cx, K.cy, w, h)
    if rect is not None:
        D = np.diag([1.0 / s, 1.0 / s, 1.0])
        size = (max(1, rect.size[0] // s), max(1, rect.size[1] // s))
        work = cv2.warpPerspective(gray, D @ rect.H, size, flags=cv2.INTER_LINEAR)
        canvas_scale = rect.px_per_m * plane.d / K.fx  # rectified px per original px at the plane
        min_dist = p.min_dist_between_circle_center * canvas_scale / s
        # the rectified image has one scale; allow for the plane's depth spread anyway
        r_lo, r_hi = _radius_bounds(p, rect.px_per_m * 1.2, rect.px_per_m / 1.2, s)
    else:
        work = cv2.resize(gray, (w // s, h // s), interpolation=cv2.INTER_AREA) if s > 1 else gray
        min_dist = p.min_dist_between_circle_center / s
        r_lo, r_hi = _radius_bounds(p, K.fx / max(z_near, 0.1), K.fx / max(z_far, 0.1), s)
    if p.use_gaussian_blur:
        k = max(1, int(p.gaussian_blur_kernel_size)) | 1
        work = cv2.GaussianBlur(work, (k, k), p.gaussian_blur_sigma)
    if debug is not None:
        debug["work"] = work
        debug["rectified"] = rect is not None
    found = cv2.HoughCircles(work, cv2.HOUGH_GRADIENT, dp=max(1.0, p.dp), minDist=max(1.0, min_dist),
                             param1=p.canny_edge_upper_threshold, param2=max(1.0, p.accumulator_threshold / s),
                             minRadius=r_lo, maxRadius=r_hi)
    out: List[Circle] = []
    if found is None:
        return out
    for cu, cv_, cr in found[0]:
        fu, fv, fr = (cu + 0.5) * s - 0.5, (cv_ + 0.5) * s - 0.5, cr * s
        if rect is not None:
            u, v = to_original(rect, fu, fv)
            pt = intersect(plane, u, v, K.fx, K.fy, K.cx, K.cy)
            if pt is None:
                continue
            radius_m = fr / rect.px_per_m
            r_px = radius_m * K.fx / pt[2]
        else:
            u, v, r_px = fu, fv, fr
            z = _rim_depth(depth_m, u, v, r_px)
            if z is None:
                continue
            pt = np.array([(u - K.cx) * z / K.fx, (v - K.cy) * z / K.fy, z])
            radius_m = r_px * z / K.fx
        if not (0 < pt[2] < p.max_depth_th) or not (p.min_radius_meters <= radius_m <= p.max_radius_meters):
            continue
        # the opening is read along the same ray as the centre: depth of the middle minus depth of the rim
        opening = _inside_depth(depth_m, u, v, r_px) - float(pt[2])
        out.append(Circle(float(u), float(v), float(r_px), float(pt[0]), float(pt[1]), float(pt[2]),
                          float(radius_m), float(opening)))
    return out
