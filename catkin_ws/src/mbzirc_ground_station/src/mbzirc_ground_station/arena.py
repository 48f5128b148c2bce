"""The page's drawing of the arena: what a team knew before the trial, from `mbzirc_arena`.

The station shows the team's own knowledge (arena bounds, floors, the buildings' outline with their windows
and doors, the facade fire holders, the ground fire places, the robots' homes), never the simulator's
private world (interior walls, which holders burn): it reads the world file through `mbzirc_arena`, which
reads only the public part.
"""
from __future__ import annotations

from typing import Optional

from mbzirc_arena.arena import Arena, ArenaError, load_arena as load_public_arena
from mbzirc_arena.c3 import ARENA as DEFAULT_ARENA

__all__ = ["ArenaError", "page_arena", "load_arena"]

WALL = 0.2   # m: drawn thickness of an outer wall


def _outline(name: str, box: tuple) -> list:
    """The four outer walls of a building as thin rectangles (x, y, z min and max)."""
    x0, y0, z0, x1, y1, z1 = box
    return [{"name": "%s_%s" % (name, side), "min": list(lo), "max": list(hi), "inner": False, "openings": []}
            for side, lo, hi in (("south", (x0, y0, z0), (x1, y0 + WALL, z1)),
                                 ("north", (x0, y1 - WALL, z0), (x1, y1, z1)),
                                 ("west", (x0, y0, z0), (x0 + WALL, y1, z1)),
                                 ("east", (x1 - WALL, y0, z0), (x1, y1, z1)))]


def _opening(o) -> dict:
    """A window or door as a segment on the map: its width along the wall, across the wall's normal."""
    (cx, cy, cz), (nx, ny) = o.centre, o.normal
    ax, ay = -ny * o.width / 2, nx * o.width / 2
    seg = [cx - ax, cy - ay, cx + ax, cy + ay]
    return {"seg": [round(v, 3) for v in seg], "z": [cz - o.height / 2, cz + o.height / 2],
            "door": o.kind == "door"}


def page_arena(arena: Arena, name: str = "") -> dict:
    """The page's arena description (plain JSON data) of the team's arena model."""
    walls, boxes = [], []
    for b in arena.buildings:
        outline = _outline(b.name, b.box)
        outline[0]["openings"] = [_opening(o) for o in arena.openings if o.building == b.name]
        walls += outline
        boxes.append({"name": "%s_roof" % b.name, "min": list(b.box[:3]), "max": list(b.box[3:])})
    bounds = list(arena.bounds)
    return {"name": name, "min": bounds[:3], "max": bounds[3:], "floors": list(arena.floor_heights),
            "walls": walls, "boxes": boxes,
            "facade_holders": [{"id": h.id, "position": list(h.position), "normal": list(h.normal)}
                               for h in arena.facade_holders],
            "ground_holders": [{"id": "g_%d" % i, "position": list(p)}
                               for i, p in enumerate(arena.ground_fire_places)],
            "homes": [{"id": str(h.robot_id), "kind": h.kind, "payload": h.payload, "home": list(h.position)}
                      for h in arena.homes]}


def load_arena(path: Optional[str]) -> dict:
    """The page's arena from a world file's public part, or the default C3 arena when no path is given."""
    if not path:
        return page_arena(DEFAULT_ARENA, "c3_default")
    return page_arena(load_public_arena(path))
