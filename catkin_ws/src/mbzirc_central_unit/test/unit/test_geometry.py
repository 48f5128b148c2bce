"""Routing around the building and through the virtual elevators."""
import math

import pytest

from mbzirc_arena import c3

from mbzirc_central_unit import constants as C
from mbzirc_central_unit import geometry as G


def _segments_clear(path, margin=0.0):
    """True if no segment of a 3D path crosses a building box it is not above."""
    for p, q in zip(path, path[1:]):
        for b in c3.BUILDING_BOXES:
            rect = (b[0] - margin, b[1] - margin, b[3] + margin, b[4] + margin)
            for s in range(21):
                t = s / 20
                x, y, z = (p[i] + t * (q[i] - p[i]) for i in range(3))
                if z < b[5] and G.inside((x, y), rect):
                    return False
    return True


def test_segment_hits_rect():
    r = (0.0, 0.0, 10.0, 10.0)
    assert G.segment_hits_rect((-1, 5), (11, 5), r)
    assert not G.segment_hits_rect((-1, -1), (11, -1), r)
    assert not G.segment_hits_rect((0, -1), (0, 11), r)  # along an edge is not inside
    assert G.segment_hits_rect((5, 5), (20, 20), r)


@pytest.mark.parametrize("start,goal", [((0, 0, 5), (30, 25, 5)), ((5, 13, 7), (40, 13, 7)),
                                         ((17, 3, 2), (17, 24, 2)), ((30, 13, 8), (5, 13, 8))])
def test_level_route_goes_around(start, goal):
    path = [start] + G.level_route(start, goal, start[2])
    assert path[-1] == goal
    assert _segments_clear(path)


def test_level_route_above_the_extension_only_avoids_the_tower():
    # At 8 m the extension (4.5 m high) is no obstacle: a straight line over it is fine.
    path = G.level_route((40, 13, 8), (26.7, 13, 8), 8)
    assert path == [(26.7, 13, 8)]


def test_plan_route_changes_altitude_only_in_the_elevator():
    for elev in (0, 1):
        path = [(0, 0, 5)] + G.plan_route((0, 0, 5), (26.7, 12.7, 10.5), elev)
        ex, ey = G.elevator_points()[elev]
        for p, q in zip(path, path[1:]):
            if abs(p[2] - q[2]) > 1e-6:
                assert (p[0], p[1]) == pytest.approx((ex, ey)) and (q[0], q[1]) == pytest.approx((ex, ey))
        assert _segments_clear(path)
        assert path[-1] == (26.7, 12.7, 10.5)


def test_elevators_are_at_opposite_corners_and_far_apart():
    a, b = G.elevator_points()
    assert math.dist(a, b) > 30
    lo, hi = G.elevator_box(0, 3, 12)
    assert lo[2] <= 3 and hi[2] >= 12


def test_facade_search_path_visits_every_holder_of_the_floor_without_crossing_the_tower():
    for floor in range(3):
        holders = [h for h in c3.FACADE_HOLDERS if G.floor_of(h[2]) == floor]
        path = G.facade_search_path(floor)
        vps = [G.viewpoint(h) for h in holders]
        for vp in vps:
            assert any(math.dist(vp[:3], p[:3]) < 1e-6 for p in path)
        assert _segments_clear([p[:3] for p in path], margin=0.5)
        for p in path:  # each waypoint stays at its floor
            assert G.floor_of(p[2]) == floor


def test_viewpoint_faces_the_wall():
    x, y, z, yaw = G.viewpoint((11.4, 8.5, 6.0))
    assert (x, y, z) == pytest.approx((11.4 - C.FACADE_STANDOFF, 8.5, 6.0)) and yaw == pytest.approx(0.0)
    x, y, z, yaw = G.viewpoint((17.4, 19.5, 10.5))
    assert y == pytest.approx(19.5 + C.FACADE_STANDOFF) and yaw == pytest.approx(-math.pi / 2)
    x, y, z, yaw = G.viewpoint((24.2, 8.2, 12.5))
    assert x == pytest.approx(24.2 + C.FACADE_STANDOFF) and abs(yaw) == pytest.approx(math.pi)


def test_ground_paths():
    path = G.ground_search_path((-2, 1.65, 3), 3.0, [(-9.0, 20.0, 0.0), (1.0, 14.0, 0.0)])
    assert len(path) == 4
    assert math.dist(path[0][:2], (1.0, 14.0)) < 0.35 and math.dist(path[1][:2], (1.0, 14.0)) < 0.35
    assert math.dist(path[2][:2], (-9.0, 20.0)) < 0.35 and math.dist(path[3][:2], (-9.0, 20.0)) < 0.35
    sweep = G.lawnmower_path((0, 0, 10, 8), 4.0, 3.0)
    assert {p[1] for p in sweep} == {0, 4, 8} and all(p[2] == 3.0 for p in sweep)


def test_elevators_keep_clear_of_outdoor_fire_holders_and_the_building():
    for e in G.elevator_points():
        assert min(math.dist(e, h[:2]) for h in c3.GROUND_FIRE_PLACES) > 4.0
        assert G.obstacle_rect(1.0, 3.0) is None or not G.inside(e, G.obstacle_rect(1.0, 3.0))


def test_facade_of_an_estimate_off_the_wall():
    """A facade fire estimate 0.3-1 m off its face (GNSS error) belongs to the nearest facade: its viewpoint
    stands in front of that face, never along another one."""
    assert G.facade_of((12.2, 19.8, 6.2)) == "A"
    x, y, z, yaw = G.viewpoint((12.2, 19.8, 6.2))
    assert y > 21.0 and abs(yaw + math.pi / 2) < 1e-9
    assert G.facade_of((10.6, 8.5, 6.0)) == "C" and G.facade_of((25.0, 12.7, 10.5)) == "D"
