"""Finding the hot spot in one 32 x 32 temperature frame: threshold -> contours -> centroid."""
from __future__ import annotations

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


def find_hot_spot(frame: np.ndarray, threshold: float, min_fire_temperature: float = 0.0) -> Optional[HotSpot]:
    """Returns the hot spot of a 32x32 frame, or None when nothing is hot enough.

    Hot pixels are those at or above max(`threshold`, `min_fire_temperature`): the original's 37 degC
    threshold alone makes a whole sun-heated facade (40-45 degC) one hot contour, so the frame is always
    "hot" and the centroid is the middle of the wall, not the fire; `min_fire_temperature` = 0 gives the
    original behaviour. The position is the plain mean of the centroids of every contour, as in the
    original; unlike the original, which kept centroids in fixed-size arrays that overflowed with many
    contours, any number of contours is handled.
    """
    valid = np.nan_to_num(frame, nan=-np.inf)
    mask = (valid >= max(threshold, min_fire_temperature)).astype(np.uint8)
    hot_pixels = int(mask.sum())
    if hot_pixels == 0:
        return None
    peak = float(valid.max())
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
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
