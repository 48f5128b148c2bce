"""The arena layout the strategy plans with: fire holders, windows, interior walls, indoor rooms.

Teams know the building and where fires *can* be; which holders burn is what they must find out. The layout
is read from the same world file the simulator builds the building from (its geometry and holder lists,
never its seed-dependent active fires), or from the defaults of c3_world.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

from . import constants as C
from .geometry import Point, Pose, floor_of, segment_hits_rect

Rect = tuple[float, float, float, float]

# Defaults = the c3_default world of ual_sim (tower windows, interior walls, holders).
DEFAULT_WINDOWS = [  # (centre x, y, z, outward normal x, y)
    (16.0, 19.5, 2.5, 0, 1), (11.4, 11.0, 2.5, -1, 0),      # ground floor (A, C)
    (15.5, 19.5, 7.5, 0, 1), (20.0, 19.5, 12.5, 0, 1),        # facade A
    (18.0, 6.7, 7.5, 0, -1), (15.0, 6.7, 12.5, 0, -1),        # facade B
    (11.4, 12.5, 7.5, -1, 0), (11.4, 12.0, 12.5, -1, 0),      # facade C
    (24.2, 14.5, 7.5, 1, 0), (24.2, 15.0, 12.5, 1, 0),        # facade D
]
DEFAULT_INNER_WALLS = [  # (xmin, ymin, zmin, xmax, ymax, zmax)
    (17.7, 6.9, f * 5.0, 17.9, 19.3, f * 5.0 + 4.5) for f in range(3)] + [
    (11.6, 15.0, f * 5.0, 17.7, 15.2, f * 5.0 + 4.5) for f in range(3)]
DEFAULT_INDOOR_HOLDERS = [  # (x, y, z, normal x, normal y)
    (17.7, 8.5, 1.5 + 5.0 * f, -1, 0) for f in range(3)] + [(17.9, 16.5, 1.5 + 5.0 * f, 1, 0) for f in range(3)]
DEFAULT_GROUND_HOLDERS = [(-9.0, 20.0, 0.0), (1.0, 14.0, 0.0), (-5.0, 28.0, 0.0), (5.0, 25.0, 0.0),
                          (-10.0, 8.0, 0.0)]

WINDOW_STANDOFF = 1.0   # m outside the window where enter_building starts
WINDOW_DEPTH = 1.5      # m inside the window after enter_building (the agents' ~entry_depth 2.5 - standoff)
HOLDER_VIEW = 2.0       # m in front of an indoor holder to look at it


@dataclass
class Room:
    """An indoor area reached through one window: where to start entering, and where to look."""
    floor: int
    entry: Pose            # outside the window, facing in (the enter_building goal)
    inner: Point           # just inside the window
    path: list[Pose]       # viewpoints inside, facing the indoor holders they cover

    def sees(self, p: Point, walls: list[Rect]) -> bool:
        """True if a straight line from the room's inner point or viewpoints reaches p without a wall
        (`walls` as thin centre lines, see `thin`)."""
        return any(line_of_sight(q, p, walls) for q in [self.inner] + self.path)


def thin(w: Rect, half: float = 0.01) -> Rect:
    """A wall reduced to its centre line: a fire on a wall face is estimated on, or a little into, that
    wall, and must count as seen from the room on its side of the wall's middle."""
    if w[2] - w[0] < w[3] - w[1]:
        c = (w[0] + w[2]) / 2
        return (c - half, w[1], c + half, w[3])
    c = (w[1] + w[3]) / 2
    return (w[0], c - half, w[2], c + half)


def line_of_sight(p: Sequence[float], q: Sequence[float], walls: list[Rect]) -> bool:
    """True if no wall cuts the straight 2D line p-q."""
    return not any(segment_hits_rect(p, q, w) for w in walls)


@dataclass
class Layout:
    """What the strategy knows of the arena."""
    facade_holders: list[Point] = field(default_factory=lambda: list(C.FACADE_HOLDERS))
    ground_holders: list[Point] = field(default_factory=lambda: list(DEFAULT_GROUND_HOLDERS))
    windows: list[tuple[float, ...]] = field(default_factory=lambda: list(DEFAULT_WINDOWS))
    inner_walls: list[tuple[float, ...]] = field(default_factory=lambda: list(DEFAULT_INNER_WALLS))
    indoor_holders: list[tuple[float, ...]] = field(default_factory=lambda: list(DEFAULT_INDOOR_HOLDERS))
    rooms: dict[int, list[Room]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.rooms:
            self.rooms = build_rooms(self)

    def walls_2d(self, floor: int) -> list[Rect]:
        """Interior walls of a floor as 2D rectangles."""
        return [(w[0], w[1], w[3], w[4]) for w in self.inner_walls if floor_of((w[2] + w[5]) / 2) == floor]

    def room_for(self, floor: int, p: Point) -> Optional[int]:
        """Index of the room of `floor` that sees the point p (nearest such room), or None."""
        walls = [thin(w) for w in self.walls_2d(floor)]
        best = [(math.dist(r.inner, p), i) for i, r in enumerate(self.rooms.get(floor, [])) if r.sees(p, walls)]
        return min(best)[1] if best else None

    def clear_indoors(self, floor: int, p: Point, q: Point) -> bool:
        """True if the straight line from p to q inside a floor crosses no interior wall's centre line."""
        return line_of_sight(p, q, [thin(w) for w in self.walls_2d(floor)])


def build_rooms(layout: Layout) -> dict[int, list[Room]]:
    """For every indoor holder, the nearest window from which it is seen without an interior wall between;
    holders sharing a window share a room."""
    rooms: dict[int, list[Room]] = {}
    for hx, hy, hz, nx, ny in layout.indoor_holders:
        floor = floor_of(hz)
        walls = layout.walls_2d(floor)
        view = (hx + HOLDER_VIEW * nx, hy + HOLDER_VIEW * ny, hz)
        yaw = math.atan2(-ny, -nx)
        best = None
        for wx, wy, wz, wnx, wny in layout.windows:
            if floor_of(wz) != floor:
                continue
            inner = (wx - WINDOW_DEPTH * wnx, wy - WINDOW_DEPTH * wny, wz)
            if any(segment_hits_rect(inner, view, w) for w in walls):
                continue
            d = math.dist(inner[:2], view[:2])
            if best is None or d < best[0]:
                entry = (wx + WINDOW_STANDOFF * wnx, wy + WINDOW_STANDOFF * wny, wz, math.atan2(-wny, -wnx))
                best = (d, entry, inner)
        if best is None:
            continue
        _, entry, inner = best
        same = [r for r in rooms.get(floor, []) if r.entry == entry]
        if same:
            same[0].path.append((*view, yaw))
        else:
            rooms.setdefault(floor, []).append(Room(floor, entry, inner, [(*view, yaw)]))
    return rooms


def load_world(world: dict[str, Any]) -> Layout:
    """Layout from a ual_sim world dictionary (its yaml): holders, tower windows, interior walls."""
    def pos(h: dict) -> Point:
        return tuple(float(v) for v in h["position"])  # type: ignore[return-value]

    facade = [pos(h) for h in world.get("facade_holders", [])] or list(C.FACADE_HOLDERS)
    ground = [pos(h) for h in world.get("ground_holders", [])] or list(DEFAULT_GROUND_HOLDERS)
    indoor = [(*pos(h), float(h.get("normal", [0, 0])[0]), float(h.get("normal", [0, 0])[1]))
              for h in world.get("indoor_holders", [])] or list(DEFAULT_INDOOR_HOLDERS)
    windows, inner = [], []
    t = C.TOWER_BOX
    for w in world.get("walls", []):
        lo, hi = [float(v) for v in w["min"]], [float(v) for v in w["max"]]
        name = str(w.get("name", ""))
        if name.startswith("inner"):
            inner.append((*lo, *hi))
            continue
        along_x = (hi[0] - lo[0]) >= (hi[1] - lo[1])
        on_tower = t[0] - 0.3 <= lo[0] and hi[0] <= t[3] + 0.3 and t[1] - 0.3 <= lo[1] and hi[1] <= t[4] + 0.3
        if not on_tower:
            continue
        for o in w.get("openings", []):
            a0, a1 = (float(v) for v in o["along"])
            z0, z1 = (float(v) for v in o["z"])
            if z0 < 0.5:   # doors are the UGV's
                continue
            zc = (z0 + z1) / 2
            if along_x:
                y = hi[1] if abs(hi[1] - t[4]) < 0.3 else lo[1]
                ny = 1 if abs(hi[1] - t[4]) < 0.3 else -1
                windows.append(((a0 + a1) / 2, y, zc, 0, ny))
            else:
                x = hi[0] if abs(hi[0] - t[3]) < 0.3 else lo[0]
                nx = 1 if abs(hi[0] - t[3]) < 0.3 else -1
                windows.append((x, (a0 + a1) / 2, zc, nx, 0))
    return Layout(facade_holders=facade, ground_holders=ground, windows=windows or list(DEFAULT_WINDOWS),
                  inner_walls=inner or list(DEFAULT_INNER_WALLS), indoor_holders=indoor)
