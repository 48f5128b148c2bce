"""sensor_msgs/Image <-> numpy without cv_bridge, with the checks a node needs against bad input."""
from __future__ import annotations

import numpy as np

_LAYOUT = {  # encoding -> (dtype, channels)
    "bgr8": (np.uint8, 3), "rgb8": (np.uint8, 3), "bgra8": (np.uint8, 4), "rgba8": (np.uint8, 4),
    "mono8": (np.uint8, 1), "16UC1": (np.uint16, 1), "mono16": (np.uint16, 1), "32FC1": (np.float32, 1),
}


def image_to_array(height: int, width: int, encoding: str, step: int, is_bigendian: int, data: bytes) -> np.ndarray:
    """The pixels of an Image message as an array (HxW or HxWxC); ValueError on anything inconsistent."""
    if encoding not in _LAYOUT:
        raise ValueError(f"unsupported encoding {encoding!r}")
    dtype, ch = _LAYOUT[encoding]
    dt = np.dtype(dtype).newbyteorder(">" if is_bigendian else "<")
    row = width * ch * dt.itemsize
    if height <= 0 or width <= 0 or step < row or len(data) < step * height:
        raise ValueError(f"{encoding} image {width}x{height} step {step} has {len(data)} bytes")
    buf = np.frombuffer(data, dtype=np.uint8, count=step * height).reshape(height, step)[:, :row]
    arr = np.ascontiguousarray(buf).view(dt).astype(dtype, copy=False)
    return arr.reshape(height, width, ch) if ch > 1 else arr.reshape(height, width)


def to_bgr(arr: np.ndarray, encoding: str) -> np.ndarray:
    """A colour image in BGR order (the camera publishes bgr8; rgb8/bgra8/rgba8 are converted)."""
    if encoding == "bgr8":
        return arr
    if encoding == "rgb8":
        return arr[:, :, ::-1].copy()
    if encoding == "bgra8":
        return np.ascontiguousarray(arr[:, :, :3])
    if encoding == "rgba8":
        return arr[:, :, 2::-1].copy()
    raise ValueError(f"colour image must be bgr8/rgb8/bgra8/rgba8, got {encoding!r}")
