"""Rules on the arena: floor of a height, kind of a fire, footprints, routing, boxes, yaw."""
import math

import numpy as np
import pytest

from mbzirc_arena import buildings as B
from mbzirc_arena import boxes as X
from mbzirc_arena import c3
from mbzirc_arena import messages as M
from mbzirc_arena import routing as R
from mbzirc_arena import yaw as Y
from mbzirc_arena.arena import floor_of


@pytest.mark.parametrize('z,floor', [(-0.5, 0), (0.0, 0), (0.75, 0), (2.75, 0), (4.7, 0), (5.0, 1), (6.0, 1),
                                     (8.25, 1), (9.99, 1), (10.0, 2), (12.75, 2), (16.0, 2), (30.0, 2)])
def test_floor_of_is_the_storey_whose_floor_is_highest_at_or_below(z, floor):
    """4.7 m is under the first floor's slab (ground floor); 16 m, above the roof, is the top storey."""
    assert c3.floor_of(z) == floor


def test_floor_of_every_facade_holder_is_its_storey():
    assert [c3.floor_of(h[2]) for h in c3.FACADE_HOLDERS] == [1, 2, 2, 2, 0, 1, 0, 2, 2, 2, 1, 2, 2, 2, 1]
    assert floor_of(3.0, (0.0, 2.5)) == 1


@pytest.mark.parametrize('p,sub', [((1, 14, 0), M.SUBTYPE_GROUND), ((12.4, 19.5, 6.5), M.SUBTYPE_FACADE),
                                   ((23.7, 19.5, 0.75), M.SUBTYPE_FACADE), ((16, 12, 1.0), M.SUBTYPE_INDOOR),
                                   ((25.0, 18.8, 12.5), M.SUBTYPE_FACADE), ((30.0, 12.0, 2.0), M.SUBTYPE_INDOOR),
                                   ((17.7, 8.5, 6.5), M.SUBTYPE_INDOOR), ((5.0, 25.0, 0.0), M.SUBTYPE_GROUND)])
def test_classify_fire(p, sub):
    """(also with a metre of GNSS error: see test_facade_fires_placed_a_metre_off_stay_facade)"""
    """Above the extension's roof, beside facade D, a fire is a facade fire, not an indoor one."""
    assert c3.classify_fire(p) == sub


def test_every_holder_of_the_default_arena_classifies_as_its_kind():
    assert all(c3.classify_fire(h) == M.SUBTYPE_FACADE for h in c3.FACADE_HOLDERS)
    assert all(c3.classify_fire(g) == M.SUBTYPE_GROUND for g in c3.GROUND_FIRE_PLACES)


def test_standing_at_counts_walls_only_up_to_their_roof():
    """A UAV in front of facade D's fires at 12.5 m is over the extension: only the tower is a wall there."""
    assert B.standing_at((25.7, 18.8, 12.5), c3.FOOTPRINTS) == [c3.TOWER]
    assert B.standing_at((25.7, 18.8, 4.8), c3.FOOTPRINTS) == [c3.TOWER, c3.EXTENSION]   # 0.5 m clearance
    assert B.standing_at((25.7, 18.8, 4.8), c3.FOOTPRINTS, 0.0) == [c3.TOWER]
    assert B.standing_at((25.7, 18.8), c3.FOOTPRINTS) == list(c3.FOOTPRINTS)
    assert B.standing_at((0, 0, 30.0), c3.FOOTPRINTS) == []


def test_nearest_face_and_footprint():
    normal, d = B.nearest_face((12.4, 22.0), c3.FOOTPRINTS)
    assert normal == (0.0, 1.0) and d == pytest.approx(2.5)
    assert B.in_footprint((15, 10), c3.FOOTPRINTS) and not B.in_footprint((0, 0), c3.FOOTPRINTS)
    assert B.nearest_face((0, 0), []) == (None, math.inf)


def test_segment_hits_rect():
    r = (0.0, 0.0, 2.0, 2.0)
    assert R.segment_hits_rect((-1, 1), (3, 1), r)
    assert not R.segment_hits_rect((-1, 3), (3, 3), r)
    assert not R.segment_hits_rect((-1, 0), (3, 0), r, shrink=1e-4)     # along the border
    assert not R.segment_hits_rect((-1, -1), (0, 0), r, shrink=1e-4)    # ends on a corner


def test_plan_2d_goes_around_the_buildings_and_refuses_a_goal_inside():
    start, goal = (5.0, 13.0), (42.0, 13.0)
    path = R.plan_2d(start, goal, c3.FOOTPRINTS, 1.0)
    assert path[0] == start and path[-1] == goal and len(path) > 2
    for a, b in zip(path[:-1], path[1:]):
        assert not any(R.segment_hits_rect(a, b, o) for o in c3.FOOTPRINTS)
    assert R.path_length(path) > math.dist(start, goal)
    assert R.plan_2d((0, 0), (5, 0), c3.FOOTPRINTS, 1.0) == [(0, 0), (5, 0)]
    assert R.plan_2d((0, 0), (15, 10), c3.FOOTPRINTS, 1.0) is None


def test_shortest_path_keeps_the_first_of_equal_ways():
    nodes = [(0, 0), (2, 0), (1, 1), (1, -1)]
    blocked = {(0, 1), (1, 0)}
    path = R.shortest_path(nodes, lambda i, j: (i, j) not in blocked, tie_tol=1e-6)
    assert path == [0, 2, 1]
    assert R.shortest_path(nodes, lambda i, j: False) is None


def test_boxes():
    a = X.make_box((1, 1, 1), (0, 0, 0))
    assert np.allclose(a[0], 0) and np.allclose(a[1], 1)
    assert X.boxes_overlap(a, X.make_box((0.5, 0.5, 0.5), (2, 2, 2)))
    assert not X.boxes_overlap(a, X.make_box((1, 0, 0), (2, 1, 1)))     # touching faces only
    assert X.point_in_box((1, 1, 1), a)
    lo, hi = X.swept_box((0, 0, 0), (1, 2, 3), 0.5)
    assert np.allclose(lo, -0.5) and np.allclose(hi, (1.5, 2.5, 3.5))
    assert X.check_point((0, 0, 5), c3.BOUNDS) is None
    assert 'NaN' in X.check_point((float('nan'), 0, 5), c3.BOUNDS)
    assert 'outside' in X.check_point((0, 0, 50), c3.BOUNDS)


def test_yaw():
    assert Y.yaw_from_quaternion(*Y.quaternion_from_yaw(1.0)) == pytest.approx(1.0)
    assert Y.yaw_from_quaternion(0, 0, 0, 0) is None
    assert Y.yaw_from_quaternion(0, 0, 2 * math.sin(0.5), 2 * math.cos(0.5)) == pytest.approx(1.0)  # unnormalised
    assert Y.wrap_angle(3 * math.pi) == pytest.approx(math.pi)


@pytest.mark.parametrize('off', [(0.0, -1.2, 0.0), (0.0, 1.2, 0.0), (0.8, -0.8, -0.3)])
def test_facade_fires_placed_a_metre_off_stay_facade(off):
    """Robots place fires with standard GNSS (about a metre of error): a facade fire estimated 1.2 m inside
    or outside its wall is still a facade fire, also the one 0.75 m above the ground (A_4)."""
    for h in c3.FACADE_HOLDERS:
        p = tuple(h[k] + off[k] for k in range(3))
        assert c3.classify_fire(p) == M.SUBTYPE_FACADE, p


@pytest.mark.parametrize('p', [(17.53, 8.09, 11.7), (18.35, 7.61, 6.3), (17.75, 7.83, 1.35), (17.7, 7.0, 11.5)])
def test_indoor_fire_near_a_wall_without_holder_stays_indoor(p):
    """Realistic seeds 101-108: the west indoor fires (1.8 m inside facade A's side wall, which has no facade
    holder) were estimated 0.4-0.9 m towards that wall, classified FACADE and never searched for again."""
    assert c3.classify_fire(p) == M.SUBTYPE_INDOOR
    assert B.classify_fire(p, c3.FOOTPRINTS) == M.SUBTYPE_FACADE      # the rule without the holders


def test_facade_fire_far_inside_its_building_from_its_holder_is_still_facade_within_reach():
    """(22.74, 7.77, 8.09): facade D's fire at (24.2, 8.2, 8.25) estimated 1.5 m inside the tower."""
    assert c3.classify_fire((22.74, 7.77, 8.09)) == M.SUBTYPE_FACADE
    # outside every footprint a fire is never indoors, holders or not
    assert c3.classify_fire((17.7, 5.5, 11.5)) == M.SUBTYPE_FACADE
