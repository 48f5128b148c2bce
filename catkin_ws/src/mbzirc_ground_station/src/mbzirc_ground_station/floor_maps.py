"""SLAM floor maps for the page: occupancy grids made compact, anchored in the arena frame (no ROS import).

Each indoor robot's hector_mapping publishes a grid in its own map frame (`<ns>/map`, the robot's pose at
its first scan); indoor_localization publishes the anchor arena -> `<ns>/map`. The page draws a map in the
arena frame, so the map's pose given to the page is the anchor composed with the grid's origin. A grid of
up to `MAX_SIDE` x `MAX_SIDE` cells is sent as one character per cell; a larger one is downsampled by whole
blocks (a block is occupied when any of its cells is, else free when any is, else unknown: walls survive
downsampling). Maps are kept out of the 10 Hz frames: the page fetches `/api/maps?since=<version>` every
few seconds and gets the maps only when the version changed.
"""
from __future__ import annotations

import hashlib
import math
import threading
from typing import Optional, Sequence

import numpy as np

__all__ = ["GridError", "compact_grid", "compose", "FloorMaps", "MAX_SIDE", "MAX_SOURCE_CELLS"]

MAX_SIDE = 256                   # cells per side sent to the page at most
MAX_SOURCE_CELLS = 4096 * 4096   # a bigger grid is refused as malformed (16 M cells: 16 MB a message)
OCCUPIED_AT = 50                 # occupancy (0-100) from which a cell counts as occupied (map_server's rule)
UNKNOWN, FREE, OCCUPIED = "u", "f", "o"


class GridError(ValueError):
    """A grid the page cannot draw (the message is the reason, for the throttled log)."""


def compact_grid(width: int, height: int, resolution: float, data: Sequence[int],
                 max_side: int = MAX_SIDE) -> dict:
    """{"w", "h", "res", "cells"}: the grid downsampled to at most max_side per side, row 0 first (at the
    origin's y), one character per cell (u unknown, f free, o occupied). GridError if malformed."""
    if not (isinstance(resolution, (int, float)) and math.isfinite(resolution) and resolution > 0):
        raise GridError("resolution %r is not a positive number" % (resolution,))
    if width <= 0 or height <= 0:
        raise GridError("empty grid %dx%d" % (width, height))
    if width * height > MAX_SOURCE_CELLS:
        raise GridError("grid %dx%d is larger than %d cells" % (width, height, MAX_SOURCE_CELLS))
    cells = np.frombuffer(data, dtype=np.int8) if isinstance(data, (bytes, bytearray)) else np.asarray(data)
    if cells.size != width * height:
        raise GridError("data has %d cells, %dx%d expected" % (cells.size, width, height))
    factor = max(1, math.ceil(max(width, height) / max_side))
    w, h = math.ceil(width / factor), math.ceil(height / factor)
    padded = np.full((h * factor, w * factor), -1, dtype=np.int16)
    padded[:height, :width] = cells.astype(np.int16).reshape(height, width)
    blocks = padded.reshape(h, factor, w, factor)
    occupied = (blocks >= OCCUPIED_AT).any(axis=(1, 3))
    free = ((blocks >= 0) & (blocks < OCCUPIED_AT)).any(axis=(1, 3))
    out = np.full((h, w), ord(UNKNOWN), dtype=np.uint8)
    out[free] = ord(FREE)
    out[occupied] = ord(OCCUPIED)
    return {"w": w, "h": h, "res": float(resolution) * factor, "cells": out.tobytes().decode("ascii")}


def compose(a: tuple, b: tuple) -> tuple:
    """The 2D pose (x, y, yaw) b expressed in a's parent frame (a: the pose of b's frame there)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2])


class FloorMaps:
    """The newest compact map of each robot, with a version that changes only when a map does.

    Args:
        min_period: seconds (of the caller's clock) between two maps accepted from one robot.
    """

    def __init__(self, min_period: float = 3.0) -> None:
        self.min_period = min_period
        self.version = 0
        self._maps: dict[str, dict] = {}
        self._accepted_at: dict[str, float] = {}
        self._lock = threading.Lock()

    def admit(self, robot: str, now: float) -> bool:
        """Whether a map of `robot` received now is looked at: at most one every min_period, malformed
        ones included (checked before any work). A clock that went back (a new trial) forgets every map."""
        with self._lock:
            last = self._accepted_at.get(robot)
            if last is not None and now < last:
                self._forget()
            elif last is not None and now - last < self.min_period:
                return False
            self._accepted_at[robot] = now
            return True

    def update(self, robot: str, grid: dict, origin_in_arena: tuple, floor: Optional[int], frame: str,
               now: float) -> bool:
        """Store robot's compact grid whose cell (0, 0) corner is at origin_in_arena (x, y, yaw);
        True if the page's maps changed."""
        pose = [round(float(v), 3) for v in origin_in_arena]
        if not all(math.isfinite(v) for v in pose):
            raise GridError("map pose %r is not finite" % (pose,))
        entry = dict(grid, robot=robot, origin=pose, floor=floor, frame=frame)
        digest = hashlib.sha1(repr(sorted((k, v) for k, v in entry.items())).encode("utf-8")).hexdigest()
        with self._lock:
            old = self._maps.get(robot)
            if old is not None and old["digest"] == digest:
                return False
            entry["digest"] = digest
            self._maps[robot] = entry
            self.version += 1
            return True

    def snapshot(self, since: Optional[int] = None) -> dict:
        """{"version", "maps": [...]} for the page; without "maps" when the page already has this version."""
        with self._lock:
            if since == self.version:
                return {"version": self.version}
            maps = [{k: v for k, v in m.items() if k != "digest"} for _, m in sorted(self._maps.items())]
            return {"version": self.version, "maps": maps}

    def clear(self) -> None:
        """Forget every map (a new trial)."""
        with self._lock:
            self._forget()

    def _forget(self) -> None:
        """clear() with the lock held."""
        self._accepted_at.clear()
        if self._maps:
            self._maps.clear()
            self.version += 1
