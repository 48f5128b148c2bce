"""The default Challenge 3 arena: the plan a team has before the trial (docs/c3_world.md, docs/arena_knowledge.md).

`ARENA` is what `arena_from_world` reads from the public part of ual_sim's default world
(`test_c3_default.py` checks that they are equal); a node given a `~world_file` loads that file's arena
instead. The module constants below are views of `ARENA`, for code that only needs one fact.
"""
from __future__ import annotations

from .arena import Arena, Building, Holder, Home, Opening

_N, _S, _W, _E = (0.0, 1.0), (0.0, -1.0), (-1.0, 0.0), (1.0, 0.0)   # outward normals of facades A, B, C, D


def _window(building: str, wall: str, centre: tuple, normal: tuple) -> Opening:
    return Opening('window', building, wall, centre, normal, 2.0, 2.0)


def _door(building: str, wall: str, centre: tuple, normal: tuple) -> Opening:
    return Opening('door', building, wall, centre, normal, 2.5, 2.0)


def _holders(facade: str, normal: tuple, positions: list) -> list:
    return [Holder(f'{facade}_{i}', p, (*normal, 0.0)) for i, p in enumerate(positions)]


ARENA = Arena(
    bounds=(-17.0, -13.0, 0.0, 43.0, 37.0, 20.0),          # 60 m x 50 m x 20 m
    floor_heights=(0.0, 5.0, 10.0),                          # walkable surface of the tower's three storeys
    buildings=(Building('tower', (11.4, 6.7, 0.0, 24.2, 19.5, 18.0)),        # roof structure up to 18 m
               Building('extension', (24.2, 6.7, 0.0, 37.0, 19.5, 4.5))),    # one storey beside facade D
    facade_holders=tuple(
        _holders('A', _N, [(12.4, 19.5, 6.5), (12.4, 19.5, 12.75), (17.4, 19.5, 10.5), (22.7, 19.5, 12.75),
                           (23.7, 19.5, 0.75)])
        + _holders('C', _W, [(11.4, 8.5, 6.0), (11.4, 18.5, 2.75), (11.4, 18.5, 10.25), (11.4, 14.5, 10.5),
                             (11.4, 8.5, 12.5)])
        + _holders('D', _E, [(24.2, 17.75, 6.0), (24.2, 12.7, 10.5), (24.2, 8.2, 12.5), (24.2, 18.8, 12.5),
                             (24.2, 8.2, 8.25)])),
    ground_fire_places=((-9.0, 20.0, 0.0), (1.0, 14.0, 0.0), (-5.0, 28.0, 0.0), (5.0, 25.0, 0.0),
                        (-10.0, 8.0, 0.0)),
    openings=(
        _window('tower', 'facade_A', (16.0, 19.5, 2.5), _N), _window('tower', 'facade_A', (15.5, 19.5, 7.5), _N),
        _window('tower', 'facade_A', (20.0, 19.5, 12.5), _N),
        _door('tower', 'facade_B', (14.25, 6.7, 1.0), _S), _window('tower', 'facade_B', (18.0, 6.7, 7.5), _S),
        _window('tower', 'facade_B', (15.0, 6.7, 12.5), _S),
        _window('tower', 'facade_C', (11.4, 11.0, 2.5), _W), _window('tower', 'facade_C', (11.4, 12.5, 7.5), _W),
        _window('tower', 'facade_C', (11.4, 12.0, 12.5), _W),
        _door('tower', 'facade_D', (24.2, 12.25, 1.0), _E), _window('tower', 'facade_D', (24.2, 14.5, 7.5), _E),
        _window('tower', 'facade_D', (24.2, 15.0, 12.5), _E),
        _window('extension', 'extension_north', (31.0, 19.5, 2.5), _N),
        _door('extension', 'extension_south', (31.25, 6.7, 1.0), _S)),
    homes=(Home(0, 'ugv', 'water', (4.0, -4.0, 0.0), 0.0), Home(1, 'uav', 'blanket', (-2.0, 1.65, 0.0), 0.0),
           Home(2, 'uav', 'water', (0.0, 0.0, 0.0), 0.0), Home(3, 'uav', 'water', (0.0, 3.3, 0.0), 0.0)),
    trial_duration=1200.0,
)

# ---- views of ARENA ---------------------------------------------------------------------------------
BOUNDS = ARENA.bounds                                # (x0, y0, z0, x1, y1, z1)
TOWER_BOX = ARENA.building('tower').box              # (x0, y0, z0, x1, y1, z1)
EXTENSION_BOX = ARENA.building('extension').box
BUILDING_BOXES = ARENA.building_boxes
TOWER = ARENA.building('tower').footprint            # (x0, y0, x1, y1, top)
EXTENSION = ARENA.building('extension').footprint
FOOTPRINTS = ARENA.footprints
FLOOR_HEIGHTS = ARENA.floor_heights
NUM_FLOORS = ARENA.num_floors
FACADE_HOLDERS = ARENA.facade_holder_positions       # (x, y, z) of every facade holder
GROUND_FIRE_PLACES = ARENA.ground_fire_places
TRIAL_DURATION = ARENA.trial_duration


def floor_of(z: float) -> int:
    """Floor index of a height in the default arena (rule: `arena.floor_of`)."""
    return ARENA.floor_of(z)


def classify_fire(position) -> int:
    """Object SUBTYPE_* of a fire at position in the default arena (rule: `buildings.classify_fire`)."""
    return ARENA.classify_fire(position)
