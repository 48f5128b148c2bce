"""Which faces of the sensed walls the thermal camera has looked at, while exploring a floor.

Why faces, not cells: an interior wall is 0.2 m thick, one cell of the exploration grid (0.25 m), so both
its faces are the same cell. Counted by cells, a look at a wall's east face from the room beside it held its
west face "looked at" too (c3_floor_plan_b seed 101, realistic: the UGV looked at the x 18 wall from the
north-east room, and never at its west face, 4 m from where it had looked around in the north-west room,
where the fire in0_w burned the whole trial). Counted by distance alone (a look within the view range of
a wall), the same: a look through the wall counts.

Rules:
- a face is an occupied cell's side towards a free 4-neighbour (the side the laser saw it from), in a row
  of MIN_FACE_RUN such sides at least along the wall (no doorway jamb, no lone return); its point is the
  middle of that side, its normal the direction to the free neighbour;
- a face is seen from a point on its normal's side whose straight line to the face's free neighbour passes
  no occupied cell (the grid as sensed: unknown space is no wall);
- a look (heading, field of view, view range) watches the faces seen from where it is made, within the
  range and the field of view;
- a viewpoint for an unwatched face is a standable cell within half the view range of it that sees it; a
  face within half the view range of a look-around is no viewpoint's aim any more, watched or not.
Pure geometry on exploration.FloorGrid (no ROS).
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .cell_states import FREE, OCCUPIED

NORMALS = np.array(((1, 0), (-1, 0), (0, 1), (0, -1)))     # the faces' order in a watched array's last axis
# cells of one face in a row, at least, that make a wall to look at: a doorway's jamb (a 0.2 m wall's end) or a
# lone return is none (their faces drew viewpoints into doorways, whose legs the laser found blocked)
MIN_FACE_RUN = 3


def new_watched(grid) -> np.ndarray:
    """No face watched yet: (nx, ny, 4) booleans, the last axis NORMALS' order."""
    return np.zeros(grid.cells.shape + (len(NORMALS),), dtype=bool)


def _in_runs(mask: np.ndarray, axis: int, run: int) -> np.ndarray:
    """The trues of mask that are in `run` or more consecutive trues along axis."""
    n = mask.shape[axis]
    if n < run:
        return np.zeros_like(mask)
    take = lambda a, b: mask[a:b] if axis == 0 else mask[:, a:b]
    windows = take(0, n - run + 1).copy()
    for k in range(1, run):
        windows &= take(k, n - run + 1 + k)
    out = np.zeros_like(mask)
    for k in range(run):
        if axis == 0:
            out[k:n - run + 1 + k] |= windows
        else:
            out[:, k:n - run + 1 + k] |= windows
    return out


def faces(grid) -> tuple:
    """Every face of the grid on a wall at least MIN_FACE_RUN cells long: (cells (N x 2), normal index (N,),
    face points (N x 2, m), normals (N x 2))."""
    occupied = grid.cells == OCCUPIED
    cells, kinds = [], []
    for k, (di, dj) in enumerate(NORMALS):
        neighbour_free = np.zeros_like(occupied)
        src = (slice(max(0, -di), grid.nx - max(0, di)), slice(max(0, -dj), grid.ny - max(0, dj)))
        dst = (slice(max(0, di), grid.nx - max(0, -di)), slice(max(0, dj), grid.ny - max(0, -dj)))
        neighbour_free[src] = grid.cells[dst] == FREE
        # along the wall: y for a face whose normal is along x, and the other way round
        found = np.argwhere(_in_runs(occupied & neighbour_free, 1 if di else 0, MIN_FACE_RUN))
        cells.append(found)
        kinds.append(np.full(len(found), k))
    cells = np.concatenate(cells) if cells else np.zeros((0, 2), dtype=int)
    kinds = np.concatenate(kinds) if kinds else np.zeros(0, dtype=int)
    normals = NORMALS[kinds].astype(float)
    points = np.stack([grid.x0 + (cells[:, 0] + 0.5) * grid.res, grid.y0 + (cells[:, 1] + 0.5) * grid.res],
                      axis=1) + 0.5 * grid.res * normals if len(cells) else np.zeros((0, 2))
    return cells, kinds, points, normals


def seen_from(grid, origins: np.ndarray, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """For pairs (origin i, face i): True where the origin is on the face's side and its straight line to
    the face's free neighbour passes no occupied cell (sampled every half cell; the origin's own cell not
    counted: the robot stands there)."""
    origins = np.asarray(origins, dtype=float).reshape(-1, 2)
    if not len(points):
        return np.zeros(0, dtype=bool)
    ahead = np.einsum('ij,ij->i', origins - points, normals) > 1e-9
    ends = points + 0.5 * grid.res * normals                   # the free neighbour's centre
    rel = ends - origins
    steps = np.maximum(1, (np.hypot(rel[:, 0], rel[:, 1]) / (0.5 * grid.res)).astype(int))
    pair = np.repeat(np.arange(len(points)), steps)
    k = np.arange(pair.size) - np.repeat(np.cumsum(steps) - steps, steps) + 1   # 1..steps: not the origin
    t = k / steps[pair]
    i = np.floor((origins[pair, 0] + rel[pair, 0] * t - grid.x0) / grid.res).astype(int)
    j = np.floor((origins[pair, 1] + rel[pair, 1] * t - grid.y0) / grid.res).astype(int)
    inside = (i >= 0) & (i < grid.nx) & (j >= 0) & (j < grid.ny)
    start = np.floor((origins[pair] - (grid.x0, grid.y0)) / grid.res).astype(int)
    own = (i == start[:, 0]) & (j == start[:, 1])
    blocked = np.zeros(len(points), dtype=bool)
    hit = inside & ~own
    hit[hit] = grid.cells[i[hit], j[hit]] == OCCUPIED
    blocked[np.unique(pair[hit])] = True
    return ahead & ~blocked


def _in_view(grid, here: Sequence[float], watched: np.ndarray, view_range: float, unwatched_only: bool) -> tuple:
    cells, kinds, points, normals = faces(grid)
    if unwatched_only and len(cells):
        keep = ~watched[cells[:, 0], cells[:, 1], kinds]
        cells, kinds, points, normals = cells[keep], kinds[keep], points[keep], normals[keep]
    d = points - np.asarray(here[:2], dtype=float)
    near = d[:, 0] ** 2 + d[:, 1] ** 2 <= view_range ** 2
    cells, kinds, points, normals = cells[near], kinds[near], points[near], normals[near]
    seen = seen_from(grid, np.repeat(np.asarray(here[:2], dtype=float)[None, :], len(points), axis=0), points, normals)
    return cells[seen], kinds[seen], points[seen]


def watch(grid, watched: np.ndarray, here: Sequence[float], heading: float, fov: float, view_range: float) -> None:
    """The faces seen from here within view_range and fov (rad, both ways half) of heading: watched."""
    cells, kinds, points = _in_view(grid, here, watched, view_range, unwatched_only=True)
    if not len(points):
        return
    off = np.arctan2(points[:, 1] - here[1], points[:, 0] - here[0]) - heading
    off = np.arctan2(np.sin(off), np.cos(off))
    look = np.abs(off) <= fov / 2
    watched[cells[look, 0], cells[look, 1], kinds[look]] = True


def wall_bearings(grid, here: Sequence[float], watched: np.ndarray, view_range: float) -> np.ndarray:
    """Bearings (rad) from here of the faces it sees within view_range not yet watched."""
    _cells, _kinds, points = _in_view(grid, here, watched, view_range, unwatched_only=True)
    return np.arctan2(points[:, 1] - here[1], points[:, 0] - here[0])


def near_unwatched_faces(grid, ok: np.ndarray, watched: np.ndarray, view_range: float,
                         looked: Sequence = ()) -> list:
    """Cells of ok (standable) within half view_range of a face not yet watched, and farther than that from
    every point looked around from (`looked`), that see it. Why half: a look from there sees more of the
    wall than the one face (as a look within the whole range would not). Why not near a look: a noisy laser
    keeps making new faces where a wall's surface cells flip between free and occupied, and a face a look
    failed to watch (at a grazing angle from the cell's centre, not from where the robot stood) stays
    unwatched; each drew one more viewpoint 0.25 m from the last (realistic seed 102: the UGV went to and
    fro between two walls of one room for 90 s; unit test: 80-100 viewpoints where 24 do without noise)."""
    cells, kinds, points, normals = faces(grid)
    if not len(cells):
        return []
    keep = ~watched[cells[:, 0], cells[:, 1], kinds]
    for x, y in (tuple(v[:2]) for v in looked):
        keep &= (points[:, 0] - x) ** 2 + (points[:, 1] - y) ** 2 > (0.5 * view_range) ** 2
    points, normals = points[keep], normals[keep]
    candidates = np.argwhere(ok)
    if not len(points) or not len(candidates):
        return []
    centres = np.stack([grid.x0 + (candidates[:, 0] + 0.5) * grid.res,
                        grid.y0 + (candidates[:, 1] + 0.5) * grid.res], axis=1)
    reach = (0.5 * view_range) ** 2
    d2 = ((centres[:, None, :] - points[None, :, :]) ** 2).sum(axis=2)       # candidates x faces
    ci, fi = np.nonzero(d2 <= reach)
    if not len(ci):
        return []
    seen = seen_from(grid, centres[ci], points[fi], normals[fi])
    return sorted({(int(candidates[c, 0]), int(candidates[c, 1])) for c in ci[seen]})


__all__ = ['NORMALS', 'new_watched', 'faces', 'seen_from', 'watch', 'wall_bearings', 'near_unwatched_faces']
