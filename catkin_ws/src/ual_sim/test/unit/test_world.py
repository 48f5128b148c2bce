"""World model: loading, wall splitting, ray casting, laser ranges, collisions, bad world files."""
import math

import numpy as np
import pytest

from ual_sim import constants as C
from ual_sim.world import GROUND, NO_HIT, WorldError, load_world, parse_world, slab_raycast, split_wall


@pytest.fixture(scope="module")
def world():
    return load_world()


def test_default_world_layout(world):
    assert [r.id for r in world.robots] == [0, 1, 2, 3]
    assert world.robots[1].payload == C.PAYLOAD_BLANKET and world.robots[2].payload == C.PAYLOAD_WATER
    assert np.allclose(world.robots[1].home, [-2.0, 1.65, 0.0])
    assert len(world.facade_holders) == 15 and len(world.indoor_holders) == 6
    assert {h.floor for h in world.facade_holders} == {0, 1, 2}


def test_split_wall_leaves_window_open():
    parts = split_wall(np.array([0.0, 0.0, 0.0]), np.array([10.0, 0.2, 5.0]),
                       [{"along": [4.0, 6.0], "z": [1.0, 3.0]}], "w")
    # no part covers the window centre, every other probe point is covered
    def solid(p):
        return any(np.all(p >= lo) and np.all(p <= hi) for lo, hi in parts)
    assert not solid(np.array([5.0, 0.1, 2.0]))
    for p in ([1.0, 0.1, 2.0], [5.0, 0.1, 0.5], [5.0, 0.1, 4.0], [9.0, 0.1, 2.0]):
        assert solid(np.array(p))
    vol = sum(np.prod(hi - lo) for lo, hi in parts)
    assert vol == pytest.approx(10 * 0.2 * 5 - 2 * 2 * 0.2)


def test_slab_raycast_matches_geometry():
    bmin, bmax = np.array([[2.0, -1.0], [5.0, -1.0]]), np.array([[3.0, 1.0], [6.0, 1.0]])
    o = np.zeros((3, 2))
    d = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0]])
    t, idx = slab_raycast(o, d, bmin, bmax)
    assert t[0] == pytest.approx(2.0) and idx[0] == 0
    assert math.isinf(t[1]) and idx[1] == -1
    assert math.isinf(t[2])


def test_laser_sees_building_at_right_range(world):
    # 3 m west of facade C (x = 11.4) at z = 6 facing east: front beam 3 m, rear beam nothing in range
    r = world.laser_scan(8.4, 9.5, 6.0, 0.0)
    assert len(r) == C.LASER_BEAMS
    assert r[C.LASER_BEAMS // 2] == pytest.approx(3.0, abs=1e-4)
    assert math.isinf(r[0])
    # facing north (yaw pi/2) from inside the tower ground floor: interior wall y = 15.0 at 5 m
    r = world.laser_scan(12.0, 10.0, 3.0, math.pi / 2)
    assert r[C.LASER_BEAMS // 2] == pytest.approx(5.0, abs=1e-4)


def test_window_is_open_to_laser(world):
    # first-floor window of facade C at y 11.5-13.5, z 6.5-8.5: the beam goes in and meets the interior wall x=17.7
    r = world.laser_scan(8.4, 12.5, 7.5, 0.0)
    assert r[C.LASER_BEAMS // 2] == pytest.approx(17.7 - 8.4, abs=1e-4)


def test_raycast_ground_and_sky(world):
    t, idx = world.raycast(np.array([0.0, 0.0, 2.0]), np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]), 50.0)
    assert t[0] == pytest.approx(2.0) and idx[0] == GROUND
    assert math.isinf(t[1]) and idx[1] == NO_HIT


def test_support_and_collisions(world):
    assert world.support_height(15.0, 10.0, 7.0) == pytest.approx(5.0)     # first-floor slab
    assert world.support_height(0.0, 0.0, 3.0) == 0.0
    assert world.support_height(18.0, 13.0, 19.0) == pytest.approx(18.0)   # roof structure
    hits = world.sphere_hits_building(np.array([[11.2, 10.0, 3.0], [8.0, 10.0, 3.0]]), 0.35)
    assert hits.tolist() == [True, False]


def test_more_uavs_get_distinct_homes():
    w = load_world(n_uavs=50, ugv=True)
    homes = np.array([r.home[:2] for r in w.robots])
    d = np.linalg.norm(homes[:, None] - homes[None], axis=2) + np.eye(len(homes)) * 99
    assert len(w.robots) == 51 and d.min() > 1.8
    assert all(w.inside_arena(r.home) for r in w.robots)


@pytest.mark.parametrize("data, msg", [
    ("not a mapping", "top level"),
    ({"arena": {"min": [0, 0, 0]}}, "max"),
    ({"arena": {"min": [0, 0, 0], "max": [1, 1, 1]}, "walls": [{"min": [0, 0, 0], "max": [1, "x", 1]}]}, "walls[0]"),
    ({"arena": {"min": [0, 0, 0], "max": [9, 9, 9]}, "boxes": [{"min": [2, 2, 2], "max": [1, 3, 3]}]}, "below"),
    ({"arena": {"min": [0, 0, 0], "max": [9, 9, 9]}, "robots": [{"id": 1, "home": [50, 0, 0]}]}, "outside"),
    ({"arena": {"min": [0, 0, 0], "max": [9, 9, 9]},
      "walls": [{"min": [0, 0, 0], "max": [5, 1, 5], "openings": [{"along": [3, 2], "z": [0, 1]}]}]}, "increasing"),
])
def test_malformed_world_gives_clear_error(data, msg):
    with pytest.raises(WorldError, match=msg.replace("[", r"\[").replace("]", r"\]")):
        parse_world(data)


def test_unreadable_and_bad_yaml(tmp_path):
    with pytest.raises(WorldError, match="cannot read"):
        load_world(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("arena: {min: [0, 0\n")
    with pytest.raises(WorldError, match="not valid YAML"):
        load_world(bad)
