"""exploration.py: a robot that knows only the tower's outline finds every room of a floor through its
doorways on its own laser, whatever the interior walls (two floor plans, neither given to it)."""
import math

import numpy as np
import pytest

from laser_world import ANGLE_MIN, INC, cast
from mbzirc_agents.exploration import CLEAR_SCANS, FREE, OCCUPIED, UNKNOWN, FloorGrid, next_viewpoint, route_to

OUTLINE = (11.4, 6.7, 24.2, 19.5)     # the tower's public footprint
T = 0.2


def outer_walls(door=(13.0, 15.5)):
    x0, y0, x1, y1 = OUTLINE
    return [(x0, y1 - T, x1, y1), (x0, y0, door[0], y0 + T), (door[1], y0, x1, y0 + T),
            (x0, y0, x0 + T, y1), (x1 - T, y0, x1, y1)]


# plan A: a wall x = 17.7..17.9 with a doorway at y 10-12, a wall y = 15..15.2 west of it, doorway x 13.5-15.5
PLAN_A = [(17.7, 6.9, 17.9, 10.0), (17.7, 12.0, 17.9, 19.3), (11.6, 15.0, 13.5, 15.2), (15.5, 15.0, 17.7, 15.2)]
# plan B: other rooms: a wall y = 12.0..12.2 across with a doorway at x 20-22, a wall x = 15.0..15.2 north
# of it with a doorway at y 16-18
PLAN_B = [(11.6, 12.0, 20.0, 12.2), (22.0, 12.0, 24.0, 12.2), (15.0, 12.2, 15.2, 16.0), (15.0, 18.0, 15.2, 19.3)]


def scan_points(here, walls, rng=None):
    """One scan's returns; with rng, the realistic profile's 1 % range noise and NaN / inf dropouts."""
    r = cast(here, 0.0, walls, noise=0.01, nan_rate=0.02, inf_rate=0.01, rng=rng) if rng else cast(here, 0.0, walls)
    a = ANGLE_MIN + INC * np.arange(len(r))
    ok = np.isfinite(r) & (r < 25.0)
    return np.stack([here[0] + r[ok] * np.cos(a[ok]), here[1] + r[ok] * np.sin(a[ok])], axis=1)


def explore(walls, start, steps=40, clearance=0.8, sight=False, view_range=0.0, noisy=False, **kw):
    """Teleporting robot: look, go to the next viewpoint (checking no leg crosses a wall), repeat."""
    grid = FloorGrid(OUTLINE, 0.25)
    here, visited, looked = tuple(start), [tuple(start)], []
    rng = np.random.default_rng(1) if noisy else None
    for _ in range(steps):
        for _k in range(3 if noisy else 1):
            grid.add_scan(here, scan_points(here, walls, rng))
        looked.append(here)
        legs = next_viewpoint(grid, here, clearance, 3, (), start if sight else None, looked, view_range, **kw)
        if legs is None:
            break
        for leg in legs:
            assert not crosses(here, leg, walls), (here, leg)
            here = leg
            visited.append(here)
    return grid, visited


def crosses(p, q, walls, half=0.3):
    """True if the segment p-q comes within `half` of a wall box (sampled)."""
    for k in range(51):
        x, y = p[0] + (q[0] - p[0]) * k / 50, p[1] + (q[1] - p[1]) * k / 50
        for x0, y0, x1, y1 in walls:
            if x0 - half < x < x1 + half and y0 - half < y < y1 + half:
                return True
    return False


def seen(visited, spot, walls):
    """True if some visited point has a free straight line to spot (it would see a fire there)."""
    return any(not crosses(v, spot, walls, half=0.0) for v in visited)


@pytest.mark.parametrize('plan, fires', [
    (PLAN_A, [(17.5, 8.5), (18.1, 16.5)]),                       # the default world's holder places
    (PLAN_B, [(14.8, 17.0), (23.8, 9.0), (20.0, 18.9)]),         # places of another floor plan
])
def test_from_the_door_every_room_is_reached_through_its_doorway(plan, fires):
    walls = outer_walls() + plan
    grid, visited = explore(walls, (14.25, 7.8))
    free = np.count_nonzero(grid.cells == FREE)
    assert free * 0.25 ** 2 > 0.85 * (12.4 * 12.4 - 6), free          # nearly the whole floor seen free
    for spot in fires:
        assert seen(visited, spot, walls), (spot, visited)


def test_in_sight_stays_in_the_room_of_the_window():
    """A UAV in through facade C's window (plan A): only its room, nothing behind a doorway."""
    walls = outer_walls() + PLAN_A
    start = (13.1, 12.5)
    _, visited = explore(walls, start, sight=True)
    assert len(visited) > 1
    for v in visited:
        assert 11.6 < v[0] < 17.7 and 6.9 < v[1] < 15.0, v            # the south-west room
        assert not crosses(start, v, walls, half=0.0)


@pytest.mark.parametrize('plan, start, held', [
    (PLAN_A, (13.1, 12.5), (17.8, 11.0)),      # realistic seed 112: held in the doorway of the wall x 17.7
    (PLAN_B, (14.25, 7.8), (21.0, 12.1)),      # another floor plan: held in the doorway of the wall y 12
])
def test_the_way_back_to_the_start_is_planned_on_the_free_space_from_where_a_leg_was_held(plan, start, held):
    """Realistic seed 112 with exploration: back to where the search started along the points visited, a
    UAV was held beside a doorway's jamb (a point where a leg had been held before) and left from there. The
    way back is a route over the free space from wherever the robot is: legs that keep off every wall, ending
    on the start itself; none through space never seen."""
    walls = outer_walls() + plan
    grid, _ = explore(walls, start)
    legs = route_to(grid, held, start, 0.8, 0.6)
    assert legs and legs[-1] == pytest.approx(start), legs
    here = held
    for leg in legs:
        assert not crosses(here, leg, walls, half=0.25), (here, leg)
        here = leg
    assert route_to(grid, start, start, 0.8, 0.6) == []
    unseen = FloorGrid(OUTLINE, 0.25)
    unseen.add_scan(start, scan_points(start, walls))
    assert route_to(unseen, start, (22.5, 17.5), 0.8, 0.6) is None      # behind walls never seen through
    assert route_to(grid, (0.0, 0.0), start, 0.8) is None                 # outside the footprint


def test_an_occupied_cell_stays_occupied_and_a_window_frees_only_the_outline():
    grid = FloorGrid(OUTLINE, 0.5)
    grid.add_scan((15.0, 10.0), np.array([[17.0, 10.0]]))
    assert grid.cells[grid.cell(17.0, 10.0)] == OCCUPIED
    grid.add_scan((15.0, 10.0), np.array([[19.0, 10.0]]))           # a later beam through it
    assert grid.cells[grid.cell(17.0, 10.0)] == OCCUPIED
    grid.add_scan((15.0, 10.0), np.array([[15.0, 30.0]]))           # out through a window: to the outline
    assert grid.cells[grid.cell(15.0, 19.2)] == FREE
    assert grid.cells[grid.cell(12.0, 18.0)] == UNKNOWN


def test_nothing_left_to_explore_is_none_and_bad_bounds_are_refused():
    walls = [(11.4, 6.7, 24.2, 6.9), (11.4, 19.3, 24.2, 19.5), (11.4, 6.7, 11.6, 19.5), (24.0, 6.7, 24.2, 19.5)]
    grid, visited = explore(walls, (17.8, 13.1))
    assert next_viewpoint(grid, visited[-1], 0.8) is None
    # what the operator reads then: the grid's counts and where the robot stands
    said = grid.summary(visited[-1], 0.8)
    assert f'{int((grid.cells == FREE).sum())} cells free' in said and 'from the outline' in said, said
    with pytest.raises(ValueError):
        FloorGrid((1.0, 1.0, 0.0, 2.0))
    assert next_viewpoint(grid, (0.0, 0.0), 0.8) is None               # outside the footprint


def test_a_room_seen_whole_from_its_window_is_still_visited_near_enough_for_the_thermal_camera():
    """From facade C's window the laser sees the whole south-west room: no frontier, so no viewpoint but
    the first, 5 m from the fire place on the interior wall (the detector's hot frames need < 5 m). With
    a view range every free cell of the room comes within it of a look-around."""
    walls = outer_walls() + PLAN_A
    start, fire = (13.1, 12.5), (17.5, 8.5)
    _, frontier_only = explore(walls, start, sight=True)
    assert min(math.dist(v, fire) for v in frontier_only) > 3.5
    _, visited = explore(walls, start, sight=True, view_range=3.5)
    assert min(math.dist(v, fire) for v in visited) <= 3.5
    for v in visited:                               # (through a doorway in straight sight, it may leave the room)
        assert not crosses(start, v, walls, half=0.0), v


def wall_distance(p, walls):
    return min(math.hypot(max(x0 - p[0], 0, p[0] - x1), max(y0 - p[1], 0, p[1] - y1)) for x0, y0, x1, y1 in walls)


def test_a_doorway_between_noisy_jambs_is_passed_at_the_pass_clearance():
    """Realistic seed 104 with exploration: from the door, the UGV's noisy laser put returns of the 2 m
    doorway's jambs a few centimetres into it; no cell of the doorway stayed 0.8 m clear on the 0.25 m
    grid, the east room was never reached and its fire burned the whole trial. Legs may narrow to the pass
    clearance (the doorway's passage is centred by the laser) and still keep 0.8 m elsewhere."""
    walls = outer_walls() + PLAN_A
    east_fire = (18.1, 16.5)
    _, visited = explore(walls, (14.25, 7.8), noisy=True, view_range=3.5, pass_clearance=0.6)
    assert seen(visited, east_fire, walls), visited
    assert any(v[0] > 17.9 for v in visited), visited
    # every leg end keeps more than the UGV's 0.6 m radius from the walls (cell centres 0.8 m from the
    # jambs' cells may lie 0.7 m from the jambs: a leg may end in the doorway's middle)
    assert min(wall_distance(v, walls) for v in visited[1:]) >= 0.7, visited


def first_viewpoints(walls, start, n, **kw):
    """The first n viewpoints (each exploration step's last leg end) of a teleporting robot."""
    grid = FloorGrid(OUTLINE, 0.25)
    here, looked, views = tuple(start), [], []
    while len(views) < n:
        grid.add_scan(here, scan_points(here, walls))
        looked.append(here)
        legs = next_viewpoint(grid, here, 0.8, 3, (), None, looked, 3.5, **kw)
        if legs is None:
            break
        here = legs[-1]
        views.append(here)
    return views


def test_viewpoints_keep_the_view_clearance_from_the_walls_where_the_room_allows():
    """A thermal camera of 33 degrees 1.2 m from a wall sees a strip 0.7 m high of it (realistic seed 104: a
    fire 1 m below a UAV's look, 1.2 m away, was never seen). From the door, the first viewpoints are 2 m
    or more from every wall (plan A's rooms are wider than 4 m); without a view clearance, the first is
    the unknown corner by the door."""
    walls = outer_walls() + PLAN_A
    near = first_viewpoints(walls, (14.25, 7.8), 4)
    assert min(wall_distance(v, walls) for v in near) < 1.5, near
    views = first_viewpoints(walls, (14.25, 7.8), 4, view_clearance=2.0)
    assert len(views) == 4 and min(wall_distance(v, walls) for v in views) >= 1.8, views


def test_a_doorway_closed_by_returns_placed_with_a_drifted_pose_opens_again():
    """Realistic seed 104 (exploration, ground floor): the UGV's returns are placed with its GNSS pose, whose
    error drifts between looks; a look whose pose was off put the doorway's jamb into the doorway, the
    cells stayed occupied ('an occupied cell stays occupied') and the east room was never reached ('no
    frontier left'). Scans that see through such a cell free it again (not a single beam: noise)."""
    walls = outer_walls() + PLAN_A
    drifted = [(x0, y0 - 0.8, x1, y1 - 0.8) for x0, y0, x1, y1 in walls]   # the pose 0.8 m north of the truth
    grid = FloorGrid(OUTLINE, 0.25)
    here, in_doorway = (15.0, 11.0), (17.8, 11.4)
    grid.add_scan(here, scan_points(here, drifted))
    assert grid.cells[grid.cell(*in_doorway)] == OCCUPIED
    grid.add_scan(here, scan_points(here, walls))
    assert grid.cells[grid.cell(*in_doorway)] == OCCUPIED              # one scan through it: not yet
    for _ in range(2):
        grid.add_scan(here, scan_points(here, walls))
    assert grid.cells[grid.cell(*in_doorway)] == FREE
    assert next_viewpoint(grid, here, 0.8, 3, pass_clearance=0.6) is not None
    assert grid.cells[grid.cell(17.8, 12.6)] == OCCUPIED                # the true jamb stays


def outline_distance(p):
    x0, y0, x1, y1 = OUTLINE
    return min(p[0] - x0, x1 - p[0], p[1] - y0, y1 - p[1])


def test_viewpoints_keep_off_the_outline_where_the_laser_looks_out_through_a_window():
    """Ideal seed 3 with exploration: in through facade A's window of floor 1, the UAV's laser looked out
    through the window at the looking height (the sill's), the cells up to the outline were free, and the
    grid's far edge, a cell past the outline, counted as the outline: viewpoints (15.5, 18.6), (15.5, 18.8),
    0.5 m from the wall's inner face; two UAVs hit the wall under the sill there. Every viewpoint keeps the
    clearance from the footprint's outline, and a UAV's outline clearance (its facade room) when given;
    kept that far off, the room's walls still come within the view range (view_walls)."""
    from laser_world import wall_boxes
    walls = wall_boxes(7.5) + PLAN_A                   # facade A's window open at the laser's height
    for sight in (True, False):
        _, visited = explore(walls, (15.5, 18.0), sight=sight, view_range=3.5, pass_clearance=0.6,
                             view_clearance=2.0)
        assert min(outline_distance(v) for v in visited[1:]) >= 0.8 - 1e-6, visited
    _, visited = explore(walls, (15.5, 17.75), sight=True, view_range=3.5, pass_clearance=0.6,
                         view_clearance=2.0, outline_clearance=1.75, view_walls=True)
    assert len(visited) > 1 and min(outline_distance(v) for v in visited) >= 1.75 - 1e-6, visited
    # kept off the outline, the room's west wall (3.9 m from the first look) still comes within view range
    assert min(v[0] for v in visited) <= 11.6 + 3.5, visited


@pytest.mark.parametrize('shift', [(0.8, 0.0), (0.6, -0.5), (0.0, 0.0)])
def test_a_uav_whose_pose_moved_nearer_the_facade_still_leaves_for_the_room(shift):
    """GNSS-denied indoor rostest, facade D's window of floor 1: after the look-around the UAV's pose, handed
    from GNSS to SLAM, stood ~0.8 m nearer facade D than where it looked from (0.9 m from the outline, its
    facade room 1.75 m): no cell around it kept the room, 'no frontier left' after one look, the fire on
    the room's far wall 4.8 m away. It leaves through cells no nearer the outline than its own, to a
    viewpoint that keeps the room; paths elsewhere still keep it."""
    from laser_world import wall_boxes
    walls = wall_boxes(6.5) + PLAN_A                   # facade D's window open at the laser's height
    looked = (22.4, 14.5)
    grid = FloorGrid(OUTLINE, 0.25)
    grid.add_scan(looked, scan_points(looked, walls))
    here = (looked[0] + shift[0], looked[1] + shift[1])
    legs = next_viewpoint(grid, here, 0.8, 3, (), looked, [looked], 3.5, pass_clearance=0.6,
                          view_clearance=2.0, outline_clearance=1.75, view_walls=True)
    assert legs is not None
    assert outline_distance(legs[-1]) >= 1.75 - 1e-6, legs
    path = [here] + legs
    for a, b in zip(path, path[1:]):                   # never nearer the outline than it stood
        for k in range(21):
            p = (a[0] + (b[0] - a[0]) * k / 20, a[1] + (b[1] - a[1]) * k / 20)
            assert outline_distance(p) >= min(1.75, outline_distance(here)) - 0.25, (p, legs)
        assert not crosses(a, b, walls), (a, b)


def test_a_viewpoint_within_the_arrival_tolerance_or_gone_to_before_is_not_chosen():
    """On-demand ugv_gnss_denied rostest: just inside its door the UGV chose a frontier cell 0.2 m from where
    its pose said it stood, arrived at once (within its 0.2 m tolerance), saw nothing new, and chose it again,
    100 times in 100 s, the fire unsearched. A viewpoint nearer than min_move is not chosen, nor one in
    `reached` (gone to before); the search goes on elsewhere."""
    walls = outer_walls() + PLAN_A
    grid = FloorGrid(OUTLINE, 0.25)
    here = (14.3, 9.0)
    grid.add_scan(here, scan_points(here, walls))
    grid.cells[grid.cell(14.3, 8.8)] = FREE              # a frontier cell beside the robot that it never resolves
    grid.cells[grid.cell(14.3, 8.55)] = UNKNOWN
    kw = dict(pass_clearance=0.6)
    first = next_viewpoint(grid, here, 0.6, 1, (), None, [here], 0.0, **kw)
    assert first is not None and math.dist(first[-1], here) < 0.3, first     # the trap: right beside it
    moved = next_viewpoint(grid, here, 0.6, 1, (), None, [here], 0.0, min_move=0.3, **kw)
    assert moved is not None and math.dist(moved[-1], here) >= 0.3, moved
    again = next_viewpoint(grid, here, 0.6, 1, (), None, [here], 0.0, reached=[first[-1]], **kw)
    assert again is not None and grid.cell(*again[-1]) != grid.cell(*first[-1]), again


def test_a_look_around_turns_only_to_walls_in_range_not_yet_looked_at():
    """Ideal seed 3 with exploration: at every viewpoint the UAV turned through 12 headings of its 33 deg
    thermal camera (35-50 s), at viewpoints 0.2-0.5 m apart that looked at the same walls again. A look
    turns only to the walls its laser sees within the view range that no earlier look held."""
    from mbzirc_agents.exploration import headings_to_watch, wall_bearings, watch
    walls = outer_walls() + PLAN_A
    grid = FloorGrid(OUTLINE, 0.25)
    here, fov, rng = (15.0, 12.0), math.radians(33.0), 3.5
    grid.add_scan(here, scan_points(here, walls))
    watched = np.zeros_like(grid.cells, dtype=bool)
    bearings = wall_bearings(grid, here, watched, rng)
    yaws = headings_to_watch(bearings, math.radians(30.0))
    assert 0 < len(yaws) < 12, yaws
    for b in bearings:                                  # every wall cell in range is in some look's view
        assert any(abs(math.remainder(b - y, 2 * math.pi)) <= math.radians(15.0) + 1e-9 for y in yaws), b
    # the south wall (y 6.9, 5.1 m away) is out of range: no look that way
    assert all(abs(math.remainder(y + math.pi / 2, 2 * math.pi)) > math.radians(30.0) for y in yaws), yaws
    for y in yaws:
        watch(grid, watched, here, y, fov, rng)
    assert len(wall_bearings(grid, here, watched, rng)) == 0                 # looked at: nothing again
    near = (15.0, 11.5)
    assert len(headings_to_watch(wall_bearings(grid, near, watched, rng), math.radians(30.0))) < len(yaws)


def _walked(grid, origin, points):
    """The rule of FloorGrid.add_scan, one sample at a time: each beam passes the cells of its samples every
    half cell up to the first outside the footprint and hits its end's cell; passed and not hit: unknown ->
    free, occupied -> one more miss (free after CLEAR_SCANS); hit: occupied, its misses 0."""
    ox, oy = origin
    hits, passed = set(), set()
    for px, py in points:
        steps = int(math.hypot(px - ox, py - oy) / (0.5 * grid.res))
        for k in range(steps):
            c = grid.cell(ox + (px - ox) * k / max(steps, 1), oy + (py - oy) * k / max(steps, 1))
            if c is None:
                break
            passed.add(c)
        if grid.cell(px, py) is not None:
            hits.add(grid.cell(px, py))
    for c in passed - hits:
        if grid.cells[c] == OCCUPIED:
            grid.misses[c] += 1
            if grid.misses[c] >= CLEAR_SCANS:
                grid.cells[c] = FREE
        elif grid.cells[c] == UNKNOWN:
            grid.cells[c] = FREE
    for c in hits:
        grid.cells[c], grid.misses[c] = OCCUPIED, 0


def test_a_scan_marks_the_cells_its_beams_walk_through_and_end_in():
    """add_scan is vectorised over the scan's samples (a look's scans had cost ~40 ms each, one cell lookup
    per sample in Python): the same cells as walking each beam, inside the floor and from outside it."""
    rng = np.random.default_rng(3)
    fast, walked = FloorGrid((11.4, 6.7, 24.2, 19.5)), FloorGrid((11.4, 6.7, 24.2, 19.5))
    for origin in [(15.0, 12.0), (20.0, 9.0), (9.0, 12.5), (15.0, 12.0), (22.5, 18.0), (15.2, 12.1)]:
        ang, r = rng.uniform(-math.pi, math.pi, 720), rng.uniform(0.05, 12.0, 720)
        pts = np.column_stack((origin[0] + r * np.cos(ang), origin[1] + r * np.sin(ang)))
        fast.add_scan(origin, pts)
        _walked(walked, origin, pts)
        assert (fast.cells == walked.cells).all() and (fast.misses == walked.misses).all(), origin
    assert (fast.cells == OCCUPIED).any() and (fast.cells == FREE).any() and (fast.misses > 0).any()
