"""The default arena (mbzirc_arena.c3) is the public part of ual_sim's default world: same building boxes,
holders, floors, openings and homes. Reading ual_sim's YAML here is a test's privilege (no non-test code
outside ual_sim reads the simulator's files)."""
import os

import pytest
import yaml

from mbzirc_arena import ArenaError, arena_from_world, load_arena
from mbzirc_arena.c3 import ARENA

WORLD = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..', 'ual_sim', 'src', 'ual_sim',
                     'worlds', 'c3_default.yaml')


@pytest.fixture(scope='module')
def world():
    with open(WORLD) as f:
        return yaml.safe_load(f)


def test_default_arena_is_the_public_part_of_ual_sims_default_world():
    assert load_arena(WORLD) == ARENA


def test_building_boxes_are_the_bounding_boxes_of_the_simulators_outer_walls(world):
    """The tags select the outer walls: the tower box holds every facade and the roof structure, the
    extension every extension wall; no interior wall is tagged."""
    solids = {w['name']: w for w in (world['walls'] + world['boxes'])}
    tower, ext = ARENA.building('tower').box, ARENA.building('extension').box
    for name in ('facade_A', 'facade_B', 'facade_C', 'facade_D', 'roof_structure'):
        lo, hi = solids[name]['min'], solids[name]['max']
        assert all(tower[k] <= lo[k] and hi[k] <= tower[k + 3] for k in range(3)), name
    assert tower[5] == solids['roof_structure']['max'][2] == 18.0
    assert ext[5] == 4.5
    assert not any('building' in w for w in world['walls'] if w['name'].startswith('inner'))


def test_holders_floors_and_homes_match_the_world(world):
    assert [h.position for h in ARENA.facade_holders] == [tuple(map(float, h['position'])) for h in world['facade_holders']]
    assert [h.id for h in ARENA.facade_holders] == [h['id'] for h in world['facade_holders']]
    assert ARENA.floor_heights == tuple(world['floors'])
    assert {h.robot_id: h.position for h in ARENA.homes} == {r['id']: tuple(map(float, r['home'])) for r in world['robots']}


def test_the_arena_never_holds_the_simulators_private_facts(world):
    """Indoor holders, interior walls and the active fires are not in the model, whatever the file says."""
    text = repr(arena_from_world(world))
    for h in world['indoor_holders']:
        assert repr(tuple(map(float, h['position']))) not in text
    assert 'inner' not in text and 'active' not in text


def test_a_world_without_building_tags_is_refused_with_a_reason():
    with pytest.raises(ArenaError, match='building'):
        arena_from_world({'arena': {'min': [0, 0, 0], 'max': [1, 1, 1]}, 'walls': [{'min': [0, 0, 0], 'max': [1, 1, 1]}]})
    with pytest.raises(ArenaError, match='arena'):
        arena_from_world({'walls': []})
