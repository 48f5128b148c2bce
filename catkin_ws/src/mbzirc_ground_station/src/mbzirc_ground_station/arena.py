"""The arena as the team knew it before the trial, read from the public part of a world file.

Only what a team knows goes to the page: arena bounds, floor heights, the building's walls seen from above
with their windows and doors, the facade fire holders, the outdoor holder places and the robots' homes.
The world file's `active` entry (which holders burn) and its thermal constants are never read.
"""
from __future__ import annotations

import math
from typing import Any, Optional

import yaml

__all__ = ["ArenaError", "arena_from_yaml", "load_arena"]


class ArenaError(ValueError):
    """A world file that cannot be drawn; the message says which entry and why."""


def _vec(entry: dict, key: str, n: int) -> list[float]:
    v = entry.get(key)
    if not isinstance(v, (list, tuple)) or len(v) != n:
        raise ArenaError("%s: %r needs %d numbers" % (entry.get("name", entry.get("id", "?")), key, n))
    out = [float(x) for x in v]
    if not all(math.isfinite(x) for x in out):
        raise ArenaError("%s: %r is not finite" % (entry.get("name", entry.get("id", "?")), key))
    return out


def _openings(wall: dict, lo: list[float], hi: list[float]) -> list[dict]:
    """Windows and doors of a wall as segments on the map (a door reaches the floor of its level)."""
    along_x = (hi[0] - lo[0]) >= (hi[1] - lo[1])
    out = []
    for o in wall.get("openings") or []:
        a0, a1 = (float(x) for x in o["along"])
        z0, z1 = (float(x) for x in o["z"])
        if along_x:
            y = (lo[1] + hi[1]) / 2
            seg = [a0, y, a1, y]
        else:
            x = (lo[0] + hi[0]) / 2
            seg = [x, a0, x, a1]
        door = any(abs(z0 - f) < 0.05 for f in (0.0, 5.0, 10.0)) and (z1 - z0) < 2.6 and z0 < 0.05
        out.append({"seg": [round(v, 3) for v in seg], "z": [z0, z1], "door": bool(door)})
    return out


def arena_from_yaml(doc: dict) -> dict:
    """The page's arena description (plain JSON data) from a parsed world file."""
    if not isinstance(doc, dict) or "arena" not in doc:
        raise ArenaError("not a world file: no 'arena' entry")
    bounds = doc["arena"]
    arena_min, arena_max = _vec(bounds, "min", 3), _vec(bounds, "max", 3)
    walls = []
    for w in doc.get("walls") or []:
        lo, hi = _vec(w, "min", 3), _vec(w, "max", 3)
        walls.append({"name": str(w.get("name", "")), "min": lo, "max": hi,
                      "inner": str(w.get("name", "")).startswith("inner"), "openings": _openings(w, lo, hi)})
    boxes = [{"name": str(b.get("name", "")), "min": _vec(b, "min", 3), "max": _vec(b, "max", 3)}
             for b in doc.get("boxes") or []]
    facade = [{"id": str(h["id"]), "position": _vec(h, "position", 3), "normal": _vec(h, "normal", 3)}
              for h in doc.get("facade_holders") or []]
    ground = [{"id": str(h["id"]), "position": _vec(h, "position", 3)} for h in doc.get("ground_holders") or []]
    homes = [{"id": str(r["id"]), "kind": str(r.get("kind", "uav")), "payload": str(r.get("payload", "")),
              "home": _vec(r, "home", 3)} for r in doc.get("robots") or []]
    floors = [float(f) for f in doc.get("floors") or [0.0, 5.0, 10.0]]
    return {"name": str(doc.get("name", "")), "min": arena_min, "max": arena_max, "floors": floors,
            "walls": walls, "boxes": boxes, "facade_holders": facade, "ground_holders": ground, "homes": homes}


def load_arena(path: str) -> dict:
    """Read a world file (yaml) and return :func:`arena_from_yaml` of it."""
    try:
        with open(path, "r", encoding="utf-8") as f:
            doc: Optional[Any] = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as ex:
        raise ArenaError("cannot read world file %s: %s" % (path, ex)) from ex
    try:
        return arena_from_yaml(doc)  # type: ignore[arg-type]
    except (KeyError, TypeError, ValueError) as ex:
        if isinstance(ex, ArenaError):
            raise
        raise ArenaError("world file %s: %s" % (path, ex)) from ex
