"""The arena layout the strategy plans with: the public arena (mbzirc_arena) and, until issue 18, the indoor plan.

Teams know the building and where fires *can* be; which holders burn is what they must find out. The public
part (facade holders, ground fire places, the tower's windows) is the arena model; the interior walls,
indoor holders and rooms are the transitional private `indoor_plan`. `load_world` is the one place both are
read from a world file (never its seed-dependent active fires).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

from mbzirc_arena import Arena, arena_from_world
from mbzirc_arena.c3 import ARENA

from .indoor_plan import IndoorPlan, Rect, Room, load_indoor_plan, window_plan  # noqa: F401  (Room: the strategy's type)

INDOOR_SEARCHES = ("plan", "explore")   # `~indoor_search`: the private plan, or exploring from the windows

Point = tuple[float, float, float]


def tower_windows(arena: Arena) -> list[tuple[float, ...]]:
    """(x, y, z, nx, ny) of every window of the tower: where the UAVs enter (doors are the UGV's)."""
    return [(*w.centre, *w.normal) for w in arena.windows("tower")]


@dataclass
class Layout:
    """What the strategy knows of the arena."""
    arena: Arena = ARENA
    indoor: Optional[IndoorPlan] = None

    def __post_init__(self) -> None:
        if self.indoor is None:
            self.indoor = IndoorPlan(windows=tower_windows(self.arena))

    # ---- public (mbzirc_arena) -----------------------------------------------------------------------
    @property
    def facade_holders(self) -> list[Point]:
        return list(self.arena.facade_holder_positions)

    @property
    def ground_holders(self) -> list[Point]:
        return list(self.arena.ground_fire_places)

    @property
    def windows(self) -> list[tuple[float, ...]]:
        return tower_windows(self.arena)

    # ---- private, transitional (indoor_plan) ---------------------------------------------------------
    @property
    def inner_walls(self) -> list[tuple[float, ...]]:
        return self.indoor.inner_walls

    @property
    def indoor_holders(self) -> list[tuple[float, ...]]:
        return self.indoor.indoor_holders

    @property
    def rooms(self) -> dict[int, list[Room]]:
        return self.indoor.rooms

    @property
    def explored(self) -> bool:
        """True when the rooms are the windows' (`~indoor_search explore`): no walls, no holders known."""
        return self.indoor.explored

    def walls_2d(self, floor: int) -> list[Rect]:
        return self.indoor.walls_2d(floor)

    def room_for(self, floor: int, p: Point) -> Optional[int]:
        return self.indoor.room_for(floor, p)

    def rooms_seeing(self, floor: int, p: Point) -> list[int]:
        return self.indoor.rooms_seeing(floor, p)

    def clear_indoors(self, floor: int, p: Point, q: Point) -> bool:
        return self.indoor.clear_indoors(floor, p, q)


def explored_layout(arena: Arena = ARENA) -> Layout:
    """The layout of `~indoor_search explore`: the public arena only (rooms: one per window)."""
    return Layout(arena=arena, indoor=window_plan(tower_windows(arena)))


def load_world(world: dict[str, Any], indoor_search: str = "plan") -> Layout:
    """Layout from a ual_sim world dictionary: its public arena and, with indoor_search 'plan'
    (transitional), its indoor plan; with 'explore' nothing private is read."""
    if indoor_search not in INDOOR_SEARCHES:
        raise ValueError(f"indoor_search {indoor_search!r} is not one of {INDOOR_SEARCHES}")
    arena = arena_from_world(world)
    if indoor_search == "explore":
        return explored_layout(arena)
    return Layout(arena=arena, indoor=load_indoor_plan(world, tower_windows(arena)))
