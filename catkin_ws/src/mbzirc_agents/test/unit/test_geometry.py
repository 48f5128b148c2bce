"""Geometry: boxes, goal checks, facade standoff poses, lawn-mower paths, 2D planning."""
import math

import numpy as np
import pytest

from mbzirc_agents import constants as C
from mbzirc_agents import geometry as g


def test_boxes_overlap_and_touching():
    a = g.make_box((0, 0, 0), (1, 1, 1))
    assert g.boxes_overlap(a, g.make_box((0.5, 0.5, 0.5), (2, 2, 2)))
    assert not g.boxes_overlap(a, g.make_box((1, 0, 0), (2, 1, 1)))      # touching faces only
    assert not g.boxes_overlap(a, g.make_box((0, 0, 1.5), (1, 1, 3)))    # above


def test_make_box_sorts_corners():
    lo, hi = g.make_box((3, 0, 5), (1, 2, 4))
    assert list(lo) == [1, 0, 4] and list(hi) == [3, 2, 5]


def test_swept_box_covers_both_ends_with_margin():
    lo, hi = g.swept_box((0, 0, 5), (10, -4, 5), 1.0)
    assert list(lo) == [-1, -5, 4] and list(hi) == [11, 1, 6]


def test_check_point():
    assert g.check_point((0, 0, 5), C.ARENA_BOX) is None
    assert 'NaN' in g.check_point((float('nan'), 0, 5), C.ARENA_BOX)
    assert 'outside' in g.check_point((0, 0, 50), C.ARENA_BOX)
    assert 'outside' in g.check_point((500, 0, 5), C.ARENA_BOX)


def test_yaw_round_trip_and_zero_quaternion():
    for yaw in (-3.0, -1.0, 0.0, 0.5, 3.1):
        assert g.yaw_from_quaternion(*g.quaternion_from_yaw(yaw)) == pytest.approx(yaw)
    assert g.yaw_from_quaternion(0, 0, 0, 0) is None


@pytest.mark.parametrize('holder,normal', [((12.4, 19.5, 6.5), (0, 1)), ((11.4, 8.5, 6.0), (-1, 0)),
                                           ((24.2, 12.7, 10.5), (1, 0))])
def test_facade_standoff_faces_the_wall(holder, normal):
    pos, yaw = g.facade_standoff(holder, C.BUILDINGS, 2.0)
    assert pos[0] == pytest.approx(holder[0] + 2 * normal[0])
    assert pos[1] == pytest.approx(holder[1] + 2 * normal[1])
    assert pos[2] == holder[2]
    # facing the wall: heading points back along -normal
    assert math.cos(yaw) == pytest.approx(-normal[0], abs=1e-9)
    assert math.sin(yaw) == pytest.approx(-normal[1], abs=1e-9)


def test_standing_at_keeps_the_buildings_that_rise_to_that_height():
    assert g.standing_at((25.7, 18.8, 12.5), C.BUILDINGS) == [C.TOWER]
    assert g.standing_at((25.7, 18.8, 4.8), C.BUILDINGS) == [C.TOWER, C.EXTENSION]   # 0.5 m clearance
    assert g.standing_at((25.7, 18.8, 4.8), C.BUILDINGS, 0.0) == [C.TOWER]
    assert g.standing_at((25.7, 18.8), C.BUILDINGS) == list(C.BUILDINGS)             # 2D: every footprint
    assert g.standing_at((0, 0, 30.0), C.BUILDINGS) == []


def test_facade_standoff_of_a_fire_above_the_extension():
    """Facade D fire 0.7 m from the north-east corner, above the extension: out along +x, facing west."""
    pos, yaw = g.facade_standoff((24.2, 18.8, 12.5), C.BUILDINGS, 1.5)
    assert pos == pytest.approx((25.7, 18.8, 12.5)) and math.cos(yaw) == pytest.approx(-1.0)


def test_facing_pose():
    pos, yaw = g.facing_pose((0, 0, 1), (5, 0, 1), 1.5)
    assert pos == pytest.approx((1.5, 0, 1)) and abs(g.wrap_angle(yaw - math.pi)) < 1e-9


def test_lawnmower_covers_area():
    pts = g.lawnmower((0, 0, 10, 6), 2.0, 4.0)
    ys = sorted({p[1] for p in pts})
    assert ys[0] == 0 and ys[-1] == 6 and max(np.diff(ys)) <= 2.0
    assert all(p[2] == 4.0 for p in pts)
    assert pts[1][0] == 10 and pts[2][0] == 10      # boustrophedon: legs alternate


def test_plan_2d_goes_around_the_building():
    start, goal = (5.0, 13.0), (45.0, 13.0)       # opposite sides of tower + extension
    path = g.plan_2d(start, goal, C.BUILDINGS, 1.0)
    assert path is not None and path[0] == start and path[-1] == goal
    for a, b in zip(path[:-1], path[1:]):
        for o in C.BUILDINGS:
            assert not g._segment_hits_rect(a, b, o[:4])
    assert g.path_length(path) > 40.0


def test_plan_2d_straight_when_free_and_none_when_goal_inside():
    assert g.plan_2d((0, 0), (5, 0), C.BUILDINGS, 1.0) == [(0, 0), (5, 0)]
    assert g.plan_2d((0, 0), (15, 10), C.BUILDINGS, 1.0) is None


def test_faces_wall():
    assert g.faces_wall((12.4, 22.0, 6.5), -math.pi / 2, C.BUILDINGS)        # 2.5 m north of facade A
    assert not g.faces_wall((12.4, 22.0, 6.5), math.pi / 2, C.BUILDINGS)     # looking away
    assert not g.faces_wall((9.2, 21.7, 6.5), -math.pi / 2, C.BUILDINGS)     # corner waypoint
    assert not g.faces_wall((30.0, 21.5, 6.5), -math.pi / 2, C.BUILDINGS)    # above the extension roof
    assert g.faces_wall((30.0, 21.5, 2.0), -math.pi / 2, C.BUILDINGS)
    assert not g.faces_wall((12.4, 22.0, 6.5), None, C.BUILDINGS)
