"""The indoor plan: interior walls and indoor fire holders, and the rooms the strategy searches through windows.

PRIVATE KNOWLEDGE, TRANSITIONAL. A team does not know the interior walls or where the indoor fires can be
before the trial; the robots must sense them (docs/arena_knowledge.md). Until issue 18 replaces this with
SLAM exploration, the strategy plans its indoor searches from the simulator's interior walls and indoor
holders: this module is the one place that knowledge enters the central unit (loaded only by
`layout.load_world` / `Layout()`), so that removing it later is one change. Nothing else may read the
private part of a world file.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

from mbzirc_arena.c3 import floor_of
from mbzirc_arena.routing import segment_hits_rect

Point = tuple[float, float, float]
Pose = tuple[float, float, float, float]  # x, y, z, yaw
Rect = tuple[float, float, float, float]

# The interior walls and indoor holders of ual_sim's default world (private; see the module docstring).
DEFAULT_INNER_WALLS = [  # (xmin, ymin, zmin, xmax, ymax, zmax)
    (17.7, 6.9, f * 5.0, 17.9, 19.3, f * 5.0 + 4.5) for f in range(3)] + [
    (11.6, 15.0, f * 5.0, 17.7, 15.2, f * 5.0 + 4.5) for f in range(3)]
DEFAULT_INDOOR_HOLDERS = [  # (x, y, z, normal x, normal y)
    (17.7, 8.5, 1.5 + 5.0 * f, -1, 0) for f in range(3)] + [(17.9, 16.5, 1.5 + 5.0 * f, 1, 0) for f in range(3)]

# m outside the window where enter_building starts: the transit there flies on GNSS, a metre off (1.0 put a
# UAV into facade B under realistic uncertainty, seed 101); the agent then centres on the window by laser
WINDOW_STANDOFF = 2.0
WINDOW_DEPTH = 1.5      # m inside the window after enter_building (the agents' ~entry_depth 3.5 - standoff)
# m inside the window where a UAV leaving through it starts its passage: the move there flies on GNSS, a
# metre off, and WINDOW_DEPTH left 1.1 m between its sphere and the wall (realistic seed 103: a UAV hit
# facade C's inner face above its window, 1 m past that point)
EXIT_DEPTH = 2.5
HOLDER_VIEW = 2.0       # m in front of an indoor holder to look at it


@dataclass
class Room:
    """An indoor area reached through one window: where to start entering, and where to look."""
    floor: int
    entry: Pose            # outside the window, facing in (the enter_building goal)
    inner: Point           # just inside the window
    path: list[Pose]       # viewpoints inside, facing the indoor holders they cover

    @property
    def exit_start(self) -> Point:
        """EXIT_DEPTH inside the window, on its normal (inner and entry lie on it)."""
        dx, dy = self.entry[0] - self.inner[0], self.entry[1] - self.inner[1]
        n = math.hypot(dx, dy)
        k = (EXIT_DEPTH - WINDOW_DEPTH) / n if n > 1e-9 else 0.0
        return (self.inner[0] - k * dx, self.inner[1] - k * dy, self.inner[2])

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
    return not any(segment_hits_rect(p, q, w, shrink=1e-4) for w in walls)


@dataclass
class IndoorPlan:
    """Interior walls, indoor holders and the rooms built from them and the tower's windows."""
    windows: list[tuple[float, ...]]   # (x, y, z, nx, ny) of the tower's windows (public, from the arena)
    inner_walls: list[tuple[float, ...]] = field(default_factory=lambda: list(DEFAULT_INNER_WALLS))
    indoor_holders: list[tuple[float, ...]] = field(default_factory=lambda: list(DEFAULT_INDOOR_HOLDERS))
    rooms: dict[int, list[Room]] = field(default_factory=dict)
    explored: bool = False   # True: no walls, no holders; one room per window, searched by exploring

    def __post_init__(self) -> None:
        if not self.rooms and not self.explored:
            self.rooms = build_rooms(self)

    def walls_2d(self, floor: int) -> list[Rect]:
        """Interior walls of a floor as 2D rectangles."""
        return [(w[0], w[1], w[3], w[4]) for w in self.inner_walls if floor_of((w[2] + w[5]) / 2) == floor]

    def room_for(self, floor: int, p: Point) -> Optional[int]:
        """Index of the room of `floor` that sees the point p (nearest such room), or None."""
        rooms = self.rooms_seeing(floor, p)
        return rooms[0] if rooms else None

    def rooms_seeing(self, floor: int, p: Point) -> list[int]:
        """Indices of the rooms of `floor` that see the point p, nearest first."""
        walls = [thin(w) for w in self.walls_2d(floor)]
        return [i for _d, i in sorted((math.dist(r.inner, p), i) for i, r in enumerate(self.rooms.get(floor, []))
                                      if r.sees(p, walls))]

    def clear_indoors(self, floor: int, p: Point, q: Point) -> bool:
        """True if the straight line from p to q inside a floor crosses no interior wall's centre line."""
        return line_of_sight(p, q, [thin(w) for w in self.walls_2d(floor)])


def facing(nx: float, ny: float) -> float:
    """Yaw looking against the outward normal (nx, ny); + 0.0 turns a -0.0 component into 0.0 so that a
    float normal gives the same yaw as an integer one (pi, not -pi, facing west)."""
    return math.atan2(-ny + 0.0, -nx + 0.0)


def build_rooms(plan: IndoorPlan) -> dict[int, list[Room]]:
    """For every indoor holder, the nearest window from which it is seen without an interior wall between;
    holders sharing a window share a room."""
    rooms: dict[int, list[Room]] = {}
    for hx, hy, hz, nx, ny in plan.indoor_holders:
        floor = floor_of(hz)
        walls = plan.walls_2d(floor)
        view = (hx + HOLDER_VIEW * nx, hy + HOLDER_VIEW * ny, hz)
        yaw = facing(nx, ny)
        best = None
        for wx, wy, wz, wnx, wny in plan.windows:
            if floor_of(wz) != floor:
                continue
            inner = (wx - WINDOW_DEPTH * wnx, wy - WINDOW_DEPTH * wny, wz)
            if any(segment_hits_rect(inner, view, w, shrink=1e-4) for w in walls):
                continue
            d = math.dist(inner[:2], view[:2])
            if best is None or d < best[0]:
                entry = (wx + WINDOW_STANDOFF * wnx, wy + WINDOW_STANDOFF * wny, wz, facing(wnx, wny))
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


def window_plan(windows: list[tuple[float, ...]]) -> IndoorPlan:
    """The indoor plan of `~indoor_search explore`: what a team knows (the windows), nothing private.

    One room per window: entered from its entry pose, searched from its inner point with no heading (the
    agents look around there and explore the floor on their laser, mbzirc_agents tasks/explore.py; a
    waypoint with a heading, as on the way out, is only gone to). Without interior walls every
    straight line indoors counts as clear (the agents' leg guard checks each against the laser), and a
    fire belongs to the room whose inner point is nearest."""
    rooms: dict[int, list[Room]] = {}
    for wx, wy, wz, nx, ny in windows:
        yaw = facing(nx, ny)
        inner = (wx - WINDOW_DEPTH * nx, wy - WINDOW_DEPTH * ny, wz)
        entry = (wx + WINDOW_STANDOFF * nx, wy + WINDOW_STANDOFF * ny, wz, yaw)
        rooms.setdefault(floor_of(wz), []).append(Room(floor_of(wz), entry, inner, [(*inner, None)]))
    return IndoorPlan(windows=windows, inner_walls=[], indoor_holders=[], rooms=rooms, explored=True)


def load_indoor_plan(world: dict[str, Any], windows: list[tuple[float, ...]]) -> IndoorPlan:
    """The indoor plan from the private part of a ual_sim world dictionary: walls named `inner*` and the
    `indoor_holders` (the defaults above when the file has none)."""
    inner = [(*map(float, w["min"]), *map(float, w["max"])) for w in world.get("walls", [])
             if str(w.get("name", "")).startswith("inner")]
    indoor = [(*map(float, h["position"]), float(h.get("normal", [0, 0])[0]), float(h.get("normal", [0, 0])[1]))
              for h in world.get("indoor_holders", [])]
    return IndoorPlan(windows=windows, inner_walls=inner or list(DEFAULT_INNER_WALLS),
                      indoor_holders=indoor or list(DEFAULT_INDOOR_HOLDERS))
