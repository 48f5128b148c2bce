"""One level of the occupancy grid: log-odds cells, per-scan ray updates, bilinear access with gradient.

Conventions (the same for every level, so that all levels share one world frame):

* cells are indexed ``[iy, ix]`` (row-major, x along a row, like nav_msgs/OccupancyGrid);
* the centre of cell ``(ix, iy)`` sits at the continuous map coordinate ``(u, v) = (ix, iy)``;
* ``corner`` is the world position of the lower-left corner of cell (0, 0), so
  ``u = (x - corner_x) / resolution - 0.5``.
"""
from __future__ import annotations

from typing import Optional

import numpy as np

from .constants import LOG_ODDS_LIMIT


def logit(p: float) -> float:
    """Log-odds of probability ``p`` (the update factors are given as probabilities)."""
    return float(np.log(p / (1.0 - p)))


class GridLevel:
    """A square log-odds occupancy grid with a probability cache for fast matching.

    Args:
        size: cells per side.
        resolution: cell size in metres.
        corner: world (x, y) of the outer corner of cell (0, 0).
        free_factor: probability of a cell a beam passes through (0.4 -> log-odds -0.405).
        occupied_factor: probability of a cell a beam ends in (0.9 -> log-odds +2.197).

    .. note::
        ``prob`` is kept in step with ``log_odds`` only for the cells an update touches, so that matching
        never converts the whole map and an update costs in proportion to the length of the rays.
    """

    def __init__(self, size: int, resolution: float, corner: tuple[float, float],
                 free_factor: float = 0.4, occupied_factor: float = 0.9) -> None:
        if size < 2 or resolution <= 0.0:
            raise ValueError(f"bad grid size {size} or resolution {resolution}")
        self.size = int(size)
        self.resolution = float(resolution)
        self.corner = np.asarray(corner, dtype=np.float64)
        self.free_log_odds = np.float32(logit(free_factor))
        self.occupied_log_odds = np.float32(logit(occupied_factor))
        self.log_odds = np.zeros((self.size, self.size), np.float32)
        self.prob = np.full((self.size, self.size), 0.5, np.float32)
        self.known = np.zeros((self.size, self.size), bool)
        # Scratch labels (0 untouched, 1 free, 2 endpoint) so that each cell changes once per scan.
        self._label = np.zeros(self.size * self.size, np.uint8)
        self._bounds: Optional[tuple[int, int, int, int]] = None   # known_bounds()

    # ---- coordinates ---------------------------------------------------------------------------
    def world_to_map(self, xy: np.ndarray) -> np.ndarray:
        """World metres (N, 2) -> continuous map coordinates (cell centres at integers)."""
        return (np.asarray(xy, np.float64) - self.corner) / self.resolution - 0.5

    def map_to_world(self, uv: np.ndarray) -> np.ndarray:
        """Continuous map coordinates (N, 2) -> world metres."""
        return (np.asarray(uv, np.float64) + 0.5) * self.resolution + self.corner

    def reset(self) -> None:
        """Forget everything (all cells back to unknown, probability 0.5)."""
        self.log_odds.fill(0.0)
        self.prob.fill(0.5)
        self.known.fill(False)
        self._bounds = None

    # ---- update --------------------------------------------------------------------------------
    def ray_cells(self, origin_xy: np.ndarray, end_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Flat indices of the cells the beams pass through (free) and end in (occupied).

        Rays are traced Bresenham-style between cell centres: ``n = max(|di|, |dj|)`` steps along the
        major axis, the minor coordinate rounded, the origin cell included, the end cell excluded from
        the free cells. Beams whose end cell is outside the grid are dropped, and so is everything when
        the origin is outside. Fully vectorised: no Python loop over beams. Free indices may repeat.
        """
        o = np.rint(self.world_to_map(np.reshape(origin_xy, (1, 2))))[0].astype(np.int64)
        empty = np.zeros(0, np.int64)
        if not (0 <= o[0] < self.size and 0 <= o[1] < self.size):
            return empty, empty
        e = np.rint(self.world_to_map(end_xy)).astype(np.int64)
        inside = np.all((e >= 0) & (e < self.size), axis=1)
        e = e[inside]
        if e.shape[0] == 0:
            return empty, empty
        d = e - o
        n = np.abs(d).max(axis=1)
        occupied = e[:, 1] * self.size + e[:, 0]
        total = int(n.sum())
        if total == 0:
            return empty, occupied
        nz = n > 0
        d, n = d[nz], n[nz]
        # Per beam: a flat-index step along the major axis plus a rounded minor-axis offset. With
        # x major, cell(t) = o + t * sign(dx) + round(t * dy / n) * size, and symmetrically for y;
        # the rounding is done in integers (half rounds up) so that it is exact.
        x_major = np.abs(d[:, 0]) >= np.abs(d[:, 1])
        major_step = np.where(x_major, np.sign(d[:, 0]), np.sign(d[:, 1]) * self.size)
        minor_d = np.where(x_major, d[:, 1], d[:, 0])
        minor_unit = np.where(x_major, self.size, 1)
        beam = np.repeat(np.arange(n.shape[0]), n)
        # t = 0 .. n_b - 1 for every beam b, laid end to end.
        starts = np.cumsum(n) - n
        t = np.arange(total, dtype=np.int64) - starts[beam]
        nb = n[beam]
        minor = (2 * t * minor_d[beam] + nb) // (2 * nb)
        free = (o[1] * self.size + o[0]) + t * major_step[beam] + minor * minor_unit[beam]
        return free, occupied

    def update(self, origin_xy: np.ndarray, end_xy: np.ndarray) -> int:
        """Insert one scan: beams from ``origin_xy`` (world, (2,)) to the endpoints ``end_xy`` (N, 2).

        Each touched cell changes exactly once: by the occupied log-odds if any beam ends in it (an
        endpoint wins over a pass-through), else by the free log-odds. Returns the number of beams
        inserted (those ending inside the grid).
        """
        free, occupied = self.ray_cells(origin_xy, end_xy)
        if free.size == 0 and occupied.size == 0:
            return 0
        self._grow_bounds(free, occupied)
        label = self._label
        # Label 1 = passed through, 2 = endpoint (written last, so it wins); keep each cell once.
        label[free] = 1
        label[occupied] = 2
        idx = np.concatenate((free, occupied))
        delta = np.where(label[idx] == 2, self.occupied_log_odds, self.free_log_odds)
        label[idx] = 0
        lo = self.log_odds.reshape(-1)
        # Repeated indices all write the same value (old + delta): each cell changes once per scan.
        new = np.clip(lo[idx] + delta, -LOG_ODDS_LIMIT, LOG_ODDS_LIMIT)
        lo[idx] = new
        self.prob.reshape(-1)[idx] = 1.0 / (1.0 + np.exp(-new))
        self.known.reshape(-1)[idx] = True
        return int(occupied.size)

    def _grow_bounds(self, free: np.ndarray, occupied: np.ndarray) -> None:
        """Grow the known box by a scan's cells: every free cell lies on a beam from the origin (the first free
        cell) to an endpoint inside the grid (ray_cells), so the box of the origin and the endpoints holds
        them all."""
        ends = occupied if free.size == 0 else np.append(occupied, free[:1])
        rows, cols = np.divmod(ends, self.size)
        box = (int(cols.min()), int(rows.min()), int(cols.max()), int(rows.max()))
        if self._bounds is not None:
            b = self._bounds
            box = (min(b[0], box[0]), min(b[1], box[1]), max(b[2], box[2]), max(b[3], box[3]))
        self._bounds = box

    def known_bounds(self) -> Optional[tuple[int, int, int, int]]:
        """(ix0, iy0, ix1, iy1), inclusive, of a box holding every cell a scan has touched (None: none).
        Kept per update from the scans' end cells: no pass over the whole grid."""
        return self._bounds

    # ---- access --------------------------------------------------------------------------------
    def interpolate(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Occupancy probability M and its world gradient (dM/dx, dM/dy) at world points (N, 2).

        Bilinear interpolation over the four cells around each point. With fractional offsets
        (a, b) from the lower-left cell, M = (1-b)((1-a) m00 + a m10) + b((1-a) m01 + a m11), so
        dM/du = (1-b)(m10 - m00) + b(m11 - m01) and dM/dv = (1-a)(m01 - m00) + a(m11 - m10):
        the x-derivative is weighted by the y-fraction and vice versa. Points whose four cells are not
        all inside the grid get M = 0 and a zero gradient (they do not pull the match).
        """
        u = (xy[:, 0] - self.corner[0]) / self.resolution - 0.5
        v = (xy[:, 1] - self.corner[1]) / self.resolution - 0.5
        fu = np.floor(u)
        fv = np.floor(v)
        a = u - fu
        b = v - fv
        i0 = fu.astype(np.int64)
        j0 = fv.astype(np.int64)
        valid = (i0 >= 0) & (i0 < self.size - 1) & (j0 >= 0) & (j0 < self.size - 1)
        f = np.where(valid, j0 * self.size + i0, 0)
        p = self.prob.reshape(-1)
        m00 = p[f]
        m10 = p[f + 1]
        m01 = p[f + self.size]
        m11 = p[f + self.size + 1]
        lower = m00 + a * (m10 - m00)
        upper = m01 + a * (m11 - m01)
        m = lower + b * (upper - lower)
        du = (1.0 - b) * (m10 - m00) + b * (m11 - m01)
        dv = upper - lower
        inv = 1.0 / self.resolution
        if not valid.all():
            m = np.where(valid, m, 0.0)
            du = np.where(valid, du, 0.0)
            dv = np.where(valid, dv, 0.0)
        return m, du * inv, dv * inv

    def occupancy_grid_data(self, box: Optional[tuple[int, int, int, int]] = None) -> np.ndarray:
        """The grid (or its cells in `box`, (ix0, iy0, ix1, iy1) inclusive) as nav_msgs/OccupancyGrid values
        (100 occupied, 0 free, -1 unknown), int8 (rows, columns)."""
        rows = slice(None) if box is None else slice(box[1], box[3] + 1)
        cols = slice(None) if box is None else slice(box[0], box[2] + 1)
        log_odds, known = self.log_odds[rows, cols], self.known[rows, cols]
        out = np.full(log_odds.shape, -1, np.int8)
        out[known & (log_odds > 0.0)] = 100
        out[known & (log_odds <= 0.0)] = 0
        return out
