"""The arena as a team knows it before the trial, and how to read it from the public part of a world file.

Public (the arena plan handed to teams): arena bounds, the buildings' outline and height, the floors'
heights, the facade fire holders, the ground fire places, the approximate places of the windows and doors,
the robots' home poses, the trial's duration. Not here, because robots must sense it: interior walls,
indoor fire holders, which holders burn (docs/arena_knowledge.md).

World file (ual_sim's YAML format): `arena`, `floors`, `trial_duration`, `facade_holders`,
`ground_holders`, `robots`, and the `walls` / `boxes` that carry a `building: <name>` tag (the outer walls,
roofs and roof structures). A building's box is the bounding box of its tagged entries; the openings of its
tagged walls are its windows and doors. Untagged walls and boxes (interior walls, slabs), `indoor_holders`
and `active` are the simulator's and are never read.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Sequence

import yaml

from . import buildings as B

Point = tuple  # (x, y, z)
Box6 = tuple   # (x_min, y_min, z_min, x_max, y_max, z_max)

DOOR_MAX_SILL = 0.5   # m: an opening whose bottom is lower than this is a door (the UGV's), else a window


class ArenaError(ValueError):
    """A world file whose public part cannot be used; the message says which entry and why."""


@dataclass(frozen=True)
class Building:
    """An outer building box: its outline and its top (roof structure included)."""
    name: str
    box: Box6

    @property
    def footprint(self) -> tuple:
        """(x_min, y_min, x_max, y_max, top): the form the footprint rules (`buildings.py`) take."""
        b = self.box
        return (b[0], b[1], b[3], b[4], b[5])


@dataclass(frozen=True)
class Holder:
    """A facade fire holder: the hole's centre on the outer wall face and the wall's outward normal."""
    id: str
    position: Point
    normal: Point


@dataclass(frozen=True)
class Opening:
    """A window or door of an outer wall; its place is known to about +-1 m (docs/c3_world.md)."""
    kind: str            # 'window' | 'door'
    building: str
    wall: str
    centre: Point        # centre of the opening on the outer face
    normal: tuple        # (nx, ny): outward unit normal of the wall
    width: float
    height: float


@dataclass(frozen=True)
class Home:
    """Where a robot starts, lands and refills."""
    robot_id: int        # 0 is the UGV
    kind: str            # 'uav' | 'ugv'
    payload: str         # 'water' | 'blanket'
    position: Point
    yaw: float


def floor_of(z: float, floor_heights: Sequence[float]) -> int:
    """Floor index of a height: the storey whose floor height is the highest at or below z.

    Rule: a height below the ground floor is the ground floor (0), a height above the top storey's floor
    (its ceiling, the roof, above the roof) is the top storey. No slack: a UAV at 4.7 m is under the
    first floor's slab (5 m) and flies on the ground floor's level.
    """
    level = 0
    for i, h in enumerate(floor_heights):
        if z >= h:
            level = i
    return level


@dataclass(frozen=True)
class Arena:
    """What a team knows of the arena before the trial (see the module docstring)."""
    bounds: Box6
    floor_heights: tuple
    buildings: tuple           # Building
    facade_holders: tuple      # Holder
    ground_fire_places: tuple  # Point: where the ground fires can be (plates under silk)
    openings: tuple            # Opening
    homes: tuple               # Home
    trial_duration: float = 1200.0

    # ---- floors and buildings ------------------------------------------------------------------------
    @property
    def num_floors(self) -> int:
        return len(self.floor_heights)

    def floor_of(self, z: float) -> int:
        """Floor index of a height (rule: `floor_of`)."""
        return floor_of(z, self.floor_heights)

    def building(self, name: str) -> Building:
        """The building of that name; KeyError when the arena has none."""
        for b in self.buildings:
            if b.name == name:
                return b
        raise KeyError(f'no building {name!r} (have {[b.name for b in self.buildings]})')

    @property
    def building_boxes(self) -> tuple:
        """Every building as (x_min, y_min, z_min, x_max, y_max, z_max)."""
        return tuple(b.box for b in self.buildings)

    @property
    def footprints(self) -> tuple:
        """Every building as (x_min, y_min, x_max, y_max, top)."""
        return tuple(b.footprint for b in self.buildings)

    def classify_fire(self, position: Sequence[float]) -> int:
        """Object SUBTYPE_* of a fire at position (rule: `buildings.classify_fire`, with the facade holders)."""
        return B.classify_fire(position, self.footprints, self.facade_holder_positions)

    # ---- holders, openings, homes --------------------------------------------------------------------
    @property
    def facade_holder_positions(self) -> tuple:
        return tuple(h.position for h in self.facade_holders)

    def windows(self, building: Optional[str] = None) -> tuple:
        """Windows (of one building, or all), in world-file order."""
        return tuple(o for o in self.openings if o.kind == 'window' and building in (None, o.building))

    def doors(self, building: Optional[str] = None) -> tuple:
        """Doors (of one building, or all), in world-file order."""
        return tuple(o for o in self.openings if o.kind == 'door' and building in (None, o.building))

    def home(self, robot_id: int) -> Home:
        """Home of a robot; KeyError when the arena lists none."""
        for h in self.homes:
            if h.robot_id == int(robot_id):
                return h
        raise KeyError(f'no home for robot {robot_id}')


# ---------------------------------------------------------------------------------------------- loading
def _vec(entry: Any, key: str, n: int, where: str) -> tuple:
    try:
        v = tuple(float(x) for x in entry[key])
    except (KeyError, TypeError, ValueError) as e:
        raise ArenaError(f'{where}: {key!r} must be {n} numbers') from e
    if len(v) != n or not all(math.isfinite(x) for x in v):
        raise ArenaError(f'{where}: {key!r} must be {n} finite numbers, got {entry[key]!r}')
    return v


def _openings(wall: dict, lo: tuple, hi: tuple, building: tuple, bname: str, where: str) -> list:
    """The openings of a tagged wall as Opening, on the wall's face that lies on the building's outline."""
    out = []
    along_x = (hi[0] - lo[0]) >= (hi[1] - lo[1])
    for k, o in enumerate(wall.get('openings') or []):
        a0, a1 = _vec(o, 'along', 2, f'{where} opening {k}')
        z0, z1 = _vec(o, 'z', 2, f'{where} opening {k}')
        kind = 'door' if z0 < DOOR_MAX_SILL else 'window'
        mid = ((a0 + a1) / 2, (z0 + z1) / 2)
        if along_x:
            outer_north = abs(hi[1] - building[4]) <= abs(lo[1] - building[1])
            centre = (mid[0], hi[1] if outer_north else lo[1], mid[1])
            normal = (0.0, 1.0 if outer_north else -1.0)
        else:
            outer_east = abs(hi[0] - building[3]) <= abs(lo[0] - building[0])
            centre = (hi[0] if outer_east else lo[0], mid[0], mid[1])
            normal = (1.0 if outer_east else -1.0, 0.0)
        out.append(Opening(kind, bname, str(wall.get('name', where)), centre, normal, a1 - a0, z1 - z0))
    return out


def arena_from_world(data: Any) -> Arena:
    """The Arena of a parsed world file (its public part only, see the module docstring)."""
    if not isinstance(data, dict) or not isinstance(data.get('arena'), dict):
        raise ArenaError("world file: a mapping with an 'arena' entry (min, max) expected")
    bounds = _vec(data['arena'], 'min', 3, 'arena') + _vec(data['arena'], 'max', 3, 'arena')
    try:
        floors = tuple(float(f) for f in data.get('floors', [0.0, 5.0, 10.0]))
    except (TypeError, ValueError) as e:
        raise ArenaError('floors: must be a list of heights') from e
    tagged: dict = {}
    for section in ('walls', 'boxes'):
        for i, w in enumerate(data.get(section) or []):
            if isinstance(w, dict) and w.get('building'):
                where = f'{section}[{i}] ({w.get("name", "?")})'
                tagged.setdefault(str(w['building']), []).append(
                    (section, w, _vec(w, 'min', 3, where), _vec(w, 'max', 3, where), where))
    if not tagged:
        raise ArenaError("world file: no wall or box carries a 'building' tag, so the building outline is unknown")
    buildings, openings = [], []
    for name, parts in tagged.items():
        box = (min(p[2][0] for p in parts), min(p[2][1] for p in parts), min(p[2][2] for p in parts),
               max(p[3][0] for p in parts), max(p[3][1] for p in parts), max(p[3][2] for p in parts))
        buildings.append(Building(name, box))
        for section, w, lo, hi, where in parts:
            if section == 'walls':
                openings += _openings(w, lo, hi, box, name, where)
    holders = tuple(Holder(str(h.get('id', f'facade_{i}')), _vec(h, 'position', 3, f'facade_holders[{i}]'),
                           _vec(h, 'normal', 3, f'facade_holders[{i}]'))
                    for i, h in enumerate(data.get('facade_holders') or []))
    ground = tuple(_vec(h, 'position', 3, f'ground_holders[{i}]') for i, h in enumerate(data.get('ground_holders') or []))
    homes = []
    for i, r in enumerate(data.get('robots') or []):
        rid = int(r['id'])
        homes.append(Home(rid, str(r.get('kind', 'ugv' if rid == 0 else 'uav')), str(r.get('payload', 'water')),
                          _vec(r, 'home', 3, f'robots[{i}]'), float(r.get('yaw', 0.0))))
    return Arena(bounds=bounds, floor_heights=floors, buildings=tuple(buildings), facade_holders=holders,
                 ground_fire_places=ground, openings=tuple(openings),
                 homes=tuple(sorted(homes, key=lambda h: h.robot_id)),
                 trial_duration=float(data.get('trial_duration', 1200.0)))


def load_arena(path: str | Path) -> Arena:
    """The Arena of a world file; ArenaError with a readable message when it cannot be used."""
    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as e:
        raise ArenaError(f'cannot read world file {path}: {e}') from e
    try:
        return arena_from_world(data)
    except ArenaError as e:
        raise ArenaError(f'world file {path}: {e}') from e
