"""Finding the hot spot in one 32 x 32 temperature frame: threshold -> contours -> centroid."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence

import cv2
import numpy as np

from fire_detector import constants as C


@dataclass(frozen=True)
class HotSpot:
    """The hot area of one frame.

    Args:
        u, v: column and row of the centroid of the contour centroids (pixels, centre of pixel 0 = 0).
        width, height: size of the bounding box of every hot contour (pixels).
        max_temperature: hottest valid pixel of the frame (deg C).
        num_contours: number of hot contours.
        hot_pixels: number of pixels at or above the threshold.
    """

    u: float
    v: float
    width: float
    height: float
    max_temperature: float
    num_contours: int
    hot_pixels: int


def parse_temperatures(data: Sequence[float]) -> np.ndarray:
    """Turns the 1024 values of a raw_temp_array message into a 32x32 float array (row 0 = top).

    Raises ValueError on a wrong length or when no value is finite, so that the node can log it and go
    on. Non-finite pixels become NaN and count as cold.
    """
    arr = np.asarray(data, dtype=np.float64)
    if arr.ndim != 1 or arr.size != C.NUM_PIXELS:
        raise ValueError(f"expected {C.NUM_PIXELS} temperatures, got {arr.size}")
    arr = np.where(np.isfinite(arr), arr, np.nan)
    if np.isnan(arr).all():
        raise ValueError("no finite temperature in the frame")
    return arr.reshape(C.IMG_HEIGHT, C.IMG_WIDTH)


def hot_mask(frame: np.ndarray, threshold: float, min_contrast: float = 0.0,
             saturation_temperature: float = math.inf) -> np.ndarray:
    """Pixels that read as flame: at or above `threshold` (the original's test) and either `min_contrast`
    degC above the frame's median (the surface the camera looks at: a flame or a heater stands out of its
    wall, a sun-heated wall does not stand out of itself) or at/above `saturation_temperature` (a camera
    close enough to see only flames has no cooler surroundings in view). min_contrast 0 = the original."""
    valid = np.nan_to_num(frame, nan=-np.inf)
    mask = valid >= threshold
    if min_contrast > 0.0:
        background = float(np.nanmedian(frame))
        mask &= (valid - background >= min_contrast) | (valid >= saturation_temperature)
    return mask.astype(np.uint8)


def _is_edge_band(contour: np.ndarray, band_max_fill: float) -> bool:
    """A hot region crossing the whole frame (left to right or top to bottom) that fills less than
    `band_max_fill` of it: the warm edge of a surface against the cold sky, not a flame (a flame that
    crosses the frame is close, and then fills most of it). A flame on that surface is then judged against
    the band itself (find_hot_spot)."""
    x, y, w, h = cv2.boundingRect(contour)
    crosses = w >= C.IMG_WIDTH or h >= C.IMG_HEIGHT
    return crosses and cv2.contourArea(contour) + len(contour) / 2.0 < band_max_fill * C.NUM_PIXELS


def find_hot_spot(frame: np.ndarray, threshold: float, min_contrast: float = 0.0,
                  saturation_temperature: float = math.inf, band_max_fill: float = 0.0) -> Optional[HotSpot]:
    """Returns the hot spot of a 32x32 frame, or None when nothing reads as flame.

    Hot pixels: `hot_mask`; contours of them that are edge bands (`_is_edge_band`, when band_max_fill > 0)
    are dropped. The position is the plain mean of the centroids of every contour, as in the original;
    unlike the original, which kept centroids in fixed-size arrays that overflowed with many contours,
    any number of contours is handled. min_contrast 0 and band_max_fill 0 give the original's test.
    """
    valid = np.nan_to_num(frame, nan=-np.inf)
    mask = hot_mask(frame, threshold, min_contrast, saturation_temperature)
    if not mask.any():
        return None
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if band_max_fill > 0.0:
        bands = [c for c in contours if _is_edge_band(c, band_max_fill)]
        if bands:
            band = np.zeros_like(mask)
            cv2.drawContours(band, bands, -1, 1, thickness=cv2.FILLED)
            band &= mask
            inner = band.astype(bool)
            # inside a band, a pixel is hot only against the band's own median (the warm surface)
            on_band = (valid - float(np.median(valid[inner])) >= min_contrast) | (valid >= saturation_temperature)
            mask = np.where(inner, mask & on_band.astype(np.uint8), mask).astype(np.uint8)
            if not mask.any():
                return None
            contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return None
    hot_pixels = int(mask.sum())
    peak = float(valid.max())
    centroids = []
    for contour in contours:
        m = cv2.moments(contour)
        if m["m00"] > 1e-9:
            centroids.append((m["m10"] / m["m00"], m["m01"] / m["m00"]))
        else:  # a one-pixel or one-line contour has no area: use the mean of its points
            pts = contour.reshape(-1, 2).astype(np.float64)
            centroids.append((float(pts[:, 0].mean()), float(pts[:, 1].mean())))
    cents = np.asarray(centroids)
    all_pts = np.vstack([c.reshape(-1, 2) for c in contours])
    x0, y0 = all_pts.min(axis=0)
    x1, y1 = all_pts.max(axis=0)
    return HotSpot(
        u=float(cents[:, 0].mean()),
        v=float(cents[:, 1].mean()),
        width=float(x1 - x0 + 1),
        height=float(y1 - y0 + 1),
        max_temperature=peak,
        num_contours=len(contours),
        hot_pixels=hot_pixels,
    )
