"""The SLAM maps of a trial as map_server files (pure NumPy, no ROS).

Each indoor robot's hector_mapping builds an occupancy grid in its own frame `<ns>/map` (the robot's pose at
its first scan); indoor_localization's anchor says where that frame is in the arena. The referee places each
grid in the arena frame with its anchor and merges the grids of one floor on a common axis-aligned grid.

Rules:
- a cell is occupied when its occupancy is >= OCCUPIED_AT (65), free when it is in 0..FREE_UPTO (19), else
  unknown: the thresholds of the files' yaml (occupied_thresh 0.65, free_thresh 0.196), so that map_server
  reads back what was written;
- merging: occupied wins over free, free over unknown (the trinary codes are ordered so that it is a max);
- placing: every output cell takes the code of the source cell under its centre, and every occupied source
  cell also marks the output cell under its own centre (a rotated one-cell wall keeps no gaps);
- the output covers the known cells of every grid (rounded out to whole cells), at the finest resolution;
- files are map_saver's: `P5` PGM, top row first (the row of largest y), 0 occupied, 254 free, 205 unknown;
  the yaml's origin is the lower-left pixel's corner in the arena frame, yaw 0.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

__all__ = ["GridError", "Grid", "ArenaMap", "grid_from_message", "trinary", "compose", "place",
           "write_map_server", "read_map_server", "map_entry", "OCCUPIED_AT", "FREE_UPTO", "UNKNOWN", "FREE", "OCCUPIED"]

OCCUPIED_AT = 65                   # occupancy (0-100) from which a cell is occupied
FREE_UPTO = 19                     # occupancy (0-100) up to which a cell is free
OCCUPIED_THRESH, FREE_THRESH = 0.65, 0.196   # the yaml's thresholds (probabilities)
UNKNOWN, FREE, OCCUPIED = 0, 1, 2  # trinary codes: merging is a max
PGM_VALUE = np.array([205, 254, 0], dtype=np.uint8)   # indexed by code
MAX_SOURCE_CELLS = 4096 * 4096     # a bigger grid is refused as malformed
MAX_OUTPUT_SIDE = 4096             # cells per side of a placed map at most (coarser resolution beyond)
BAND_ROWS = 256                    # output rows sampled at once


class GridError(ValueError):
    """A grid that cannot be a map (the message says why, for the throttled log)."""


@dataclass(frozen=True)
class Grid:
    """An occupancy grid as received: cells (height, width) of occupancy -1..100, row 0 at the origin;
    origin = (x, y, yaw) of cell (0, 0)'s outer corner in the grid's own frame."""
    cells: np.ndarray
    resolution: float
    origin: tuple


@dataclass(frozen=True)
class ArenaMap:
    """Trinary codes (height, width) on an axis-aligned arena-frame grid, row 0 at the lowest y;
    origin = (x, y) of cell (0, 0)'s lower-left corner."""
    codes: np.ndarray
    resolution: float
    origin: tuple

    @property
    def extent(self) -> tuple:
        """(x_min, x_max, y_min, y_max), the form matplotlib's imshow takes."""
        h, w = self.codes.shape
        x0, y0 = self.origin
        return (x0, x0 + w * self.resolution, y0, y0 + h * self.resolution)

    def count(self, code: int) -> int:
        return int(np.count_nonzero(self.codes == code))


def grid_from_message(width: int, height: int, resolution: float, origin: tuple, data: Sequence[int]) -> Grid:
    """A Grid from an OccupancyGrid's fields; GridError when they do not make one."""
    if not (isinstance(resolution, (int, float)) and math.isfinite(resolution) and resolution > 0):
        raise GridError(f"resolution {resolution!r} is not a positive number")
    if width <= 0 or height <= 0:
        raise GridError(f"empty grid {width}x{height}")
    if width * height > MAX_SOURCE_CELLS:
        raise GridError(f"grid {width}x{height} is larger than {MAX_SOURCE_CELLS} cells")
    if len(origin) != 3 or not all(math.isfinite(v) for v in origin):
        raise GridError(f"origin {origin!r} is not a finite (x, y, yaw)")
    cells = np.frombuffer(data, dtype=np.int8) if isinstance(data, (bytes, bytearray)) \
        else np.asarray(data, dtype=np.int8)
    if cells.size != width * height:
        raise GridError(f"data has {cells.size} cells, {width}x{height} expected")
    return Grid(cells.reshape(height, width), float(resolution), tuple(float(v) for v in origin))


def trinary(cells: np.ndarray) -> np.ndarray:
    """Codes (UNKNOWN, FREE, OCCUPIED) of occupancy values by the thresholds of the module's rules."""
    c = np.asarray(cells, dtype=np.int16)
    out = np.full(c.shape, UNKNOWN, dtype=np.uint8)
    out[(c >= 0) & (c <= FREE_UPTO)] = FREE
    out[(c >= OCCUPIED_AT) & (c <= 100)] = OCCUPIED
    return out


def compose(a: tuple, b: tuple) -> tuple:
    """The 2D pose (x, y, yaw) b, given in a frame whose pose is a, in a's parent frame."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], a[2] + b[2])


def _known_box(codes: np.ndarray, res: float, pose: tuple) -> Optional[tuple]:
    """Arena-frame (x0, y0, x1, y1) around the known cells of a grid at `pose`, None if none is known."""
    rows, cols = np.nonzero(codes != UNKNOWN)
    if rows.size == 0:
        return None
    corners = [(cx * res, cy * res) for cx in (cols.min(), cols.max() + 1) for cy in (rows.min(), rows.max() + 1)]
    pts = [compose(pose, (x, y, 0.0)) for x, y in corners]
    return (min(p[0] for p in pts), min(p[1] for p in pts), max(p[0] for p in pts), max(p[1] for p in pts))


def _to_grid_cells(pose: tuple, res: float, x: np.ndarray, y: np.ndarray) -> tuple:
    """(row, col) indices, in a grid at `pose` of cell size res, of arena points (x, y)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = x - pose[0], y - pose[1]
    return np.floor((-s * dx + c * dy) / res).astype(np.int64), np.floor((c * dx + s * dy) / res).astype(np.int64)


def place(grids: Sequence[tuple]) -> Optional[ArenaMap]:
    """Merge grids, each given as (Grid, anchor = pose of its frame in the arena), on one arena-frame map
    (rules in the module docstring); None when no grid has a known cell."""
    placed = []
    for grid, anchor in grids:
        codes = trinary(grid.cells)
        pose = compose(anchor, grid.origin)
        box = _known_box(codes, grid.resolution, pose)
        if box is not None:
            placed.append((codes, grid.resolution, pose, box))
    if not placed:
        return None
    res = min(p[1] for p in placed)
    x0, y0 = min(p[3][0] for p in placed), min(p[3][1] for p in placed)
    x1, y1 = max(p[3][2] for p in placed), max(p[3][3] for p in placed)
    res = max(res, max(x1 - x0, y1 - y0) / MAX_OUTPUT_SIDE)
    w, h = max(1, math.ceil((x1 - x0) / res - 1e-9)), max(1, math.ceil((y1 - y0) / res - 1e-9))
    out = np.zeros((h, w), dtype=np.uint8)
    cx = x0 + (np.arange(w) + 0.5) * res
    for codes, gres, pose, _ in placed:
        for top in range(0, h, BAND_ROWS):                 # each output cell samples the grid (in bands:
            band = out[top:top + BAND_ROWS]                # a few MB at a time, not a 4096 x 4096 mesh)
            gx, gy = np.meshgrid(cx, y0 + (np.arange(top, top + band.shape[0]) + 0.5) * res)
            r, c = _to_grid_cells(pose, gres, gx, gy)
            inside = (r >= 0) & (r < codes.shape[0]) & (c >= 0) & (c < codes.shape[1])
            np.maximum(band, np.where(inside, codes[np.clip(r, 0, codes.shape[0] - 1),
                                                    np.clip(c, 0, codes.shape[1] - 1)], UNKNOWN), out=band)
        rows, cols = np.nonzero(codes == OCCUPIED)           # and every wall cell marks its own place
        if rows.size:
            cs, sn = math.cos(pose[2]), math.sin(pose[2])
            lx, ly = (cols + 0.5) * gres, (rows + 0.5) * gres
            ox = np.floor((pose[0] + cs * lx - sn * ly - x0) / res).astype(np.int64)
            oy = np.floor((pose[1] + sn * lx + cs * ly - y0) / res).astype(np.int64)
            ok = (ox >= 0) & (ox < w) & (oy >= 0) & (oy < h)
            out[oy[ok], ox[ok]] = OCCUPIED
    return ArenaMap(out, float(res), (float(x0), float(y0)))


def map_entry(floor: int, robots: list, stem: str, m: ArenaMap) -> dict:
    """summary.json's entry of one floor map written as `stem`.pgm/.yaml."""
    h, w = m.codes.shape
    return {"floor": floor, "robots": robots, "yaml": stem + ".yaml", "image": stem + ".pgm",
            "resolution": round(m.resolution, 4), "origin": [round(v, 3) for v in m.origin], "size": [w, h],
            "occupied_cells": m.count(OCCUPIED), "free_cells": m.count(FREE)}


def write_map_server(m: ArenaMap, directory: str, stem: str) -> str:
    """Write `<stem>.pgm` and `<stem>.yaml` (map_saver's format) into directory; the yaml's path."""
    h, w = m.codes.shape
    pgm = os.path.join(directory, stem + ".pgm")
    with open(pgm, "wb") as f:
        f.write(f"P5\n# CREATOR: mbzirc_referee {m.resolution:.3f} m/pix\n{w} {h}\n255\n".encode("ascii"))
        f.write(PGM_VALUE[m.codes[::-1]].tobytes())        # top row first
    path = os.path.join(directory, stem + ".yaml")
    with open(path, "w", encoding="utf-8") as f:
        f.write(f"image: {stem}.pgm\nresolution: {m.resolution:f}\norigin: [{m.origin[0]:f}, {m.origin[1]:f}, "
                f"0.000000]\nnegate: 0\noccupied_thresh: {OCCUPIED_THRESH}\nfree_thresh: {FREE_THRESH}\n")
    return path


def _pgm(path: str) -> np.ndarray:
    """The pixels (rows top first) of a binary 8-bit PGM."""
    with open(path, "rb") as f:
        data = f.read()
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end].decode("ascii"))
        pos = end
    if fields[0] != "P5" or int(fields[3]) != 255:
        raise GridError(f"{path}: not an 8-bit binary PGM")
    w, h = int(fields[1]), int(fields[2])
    return np.frombuffer(data[pos + 1:pos + 1 + w * h], dtype=np.uint8).reshape(h, w)


def read_map_server(yaml_path: str) -> ArenaMap:
    """A map_server yaml + image read as map_server's trinary mode does (p = (255 - v) / 255: occupied above
    occupied_thresh, free below free_thresh); the origin's yaw must be 0."""
    import yaml
    with open(yaml_path, encoding="utf-8") as f:
        meta = yaml.safe_load(f)
    image = os.path.join(os.path.dirname(yaml_path), meta["image"])
    pixels = _pgm(image)[::-1].astype(np.float64)
    if meta.get("negate", 0):
        pixels = 255.0 - pixels
    p = (255.0 - pixels) / 255.0
    codes = np.full(p.shape, UNKNOWN, dtype=np.uint8)
    codes[p > float(meta["occupied_thresh"])] = OCCUPIED
    codes[p < float(meta["free_thresh"])] = FREE
    if abs(float(meta["origin"][2])) > 1e-9:
        raise GridError(f"{yaml_path}: a rotated origin is not read here")
    return ArenaMap(codes, float(meta["resolution"]), (float(meta["origin"][0]), float(meta["origin"][1])))
