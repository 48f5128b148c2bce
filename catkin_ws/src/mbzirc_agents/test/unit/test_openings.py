"""The opening finder (openings.py) on synthetic scans, and the passage controller (control.OpeningPassage).

Scans are ray cast (laser_world.cast) against a wall 0.2 m thick ahead of the robot (x = d in the body
frame, the robot at the origin facing +x), with openings cut into it and, when asked, a far wall behind.
"""
import math

import numpy as np
import pytest

from laser_world import ANGLE_MIN, INC, THICK, cast
from mbzirc_agents.control import OpeningPassage
from mbzirc_agents.openings import find_opening, find_openings, side_clearances


def wall(d, solid, far=None):
    """Boxes of a wall at x = d..d+THICK made of the solid y-intervals, and a far wall at x = far."""
    boxes = [(d, y0, d + THICK, y1) for y0, y1 in solid]
    if far is not None:
        boxes.append((far, -30.0, far + THICK, 30.0))
    return boxes


def with_gaps(gaps, extent=(-8.0, 8.0)):
    """The solid intervals of a wall spanning extent with the gaps (y0, y1) open."""
    solid, s = [], extent[0]
    for g0, g1 in sorted(gaps):
        solid.append((s, g0))
        s = g1
    return solid + [(s, extent[1])]


def scan(boxes, yaw=0.0, origin=(0.0, 0.0), **noise):
    rng = np.random.default_rng(noise.pop('seed')) if 'seed' in noise else None
    return cast(origin, yaw, boxes, rng=rng, **noise)


def find(r, width=2.0, **kw):
    return find_opening(r, ANGLE_MIN, INC, width, **kw)


def test_a_centred_window():
    o = find(scan(wall(1.0, with_gaps([(-1.0, 1.0)]), far=7.0)))
    assert o is not None
    assert abs(o.lateral) < 0.02 and abs(o.width - 2.0) < 0.05 and abs(o.distance - 1.0) < 0.02


def test_a_window_aside():
    o = find(scan(wall(1.5, with_gaps([(-0.3, 1.7)]), far=7.0)))
    assert o is not None and abs(o.lateral - 0.7) < 0.03 and abs(o.width - 2.0) < 0.06
    o = find(scan(wall(1.5, with_gaps([(-2.1, -0.1)]), far=7.0)))
    assert o is not None and abs(o.lateral + 1.1) < 0.03


@pytest.mark.parametrize('seed', range(20))
def test_noise_and_dropouts(seed):
    """The realistic profile's laser (1 % range noise, 1 % NaN, 2 % inf) and a window 0.6 m aside."""
    r = scan(wall(1.2, with_gaps([(-0.4, 1.6)]), far=6.0), noise=0.01, nan_rate=0.01, inf_rate=0.02, seed=seed)
    o = find(r)
    assert o is not None and abs(o.lateral - 0.6) < 0.05 and abs(o.width - 2.0) < 0.1


def test_many_nan_beams():
    r = scan(wall(1.0, with_gaps([(-1.0, 1.0)]), far=6.0), noise=0.01, nan_rate=0.3, seed=3)
    o = find(r)
    assert o is not None and abs(o.lateral) < 0.1


def test_inside_looking_out_into_the_open():
    """Leaving: the window seen from inside, nothing beyond it (no returns: inf)."""
    o = find(scan(wall(1.5, with_gaps([(-0.8, 1.2)]))))
    assert o is not None and abs(o.lateral - 0.2) < 0.03


def test_the_door_from_the_ugv_standoff():
    o = find(scan(wall(2.7, with_gaps([(-1.0, 1.5)]), far=10.0)), width=2.5)
    assert o is not None and abs(o.lateral - 0.25) < 0.05 and abs(o.width - 2.5) < 0.1


def test_a_small_yaw_error():
    r = scan(wall(1.5, with_gaps([(-1.0, 1.0)]), far=7.0), yaw=math.radians(6))
    o = find(r)
    assert o is not None and abs(o.lateral) < 0.2 and abs(o.width - 2.0) < 0.2


@pytest.mark.parametrize('far', [None, 5.0])
def test_a_building_corner_is_no_window(far):
    """The wall ends 0.5 m left of the heading (nothing, or something far, beyond): open on one side."""
    boxes = wall(1.2, [(-8.0, 0.5)])
    if far is not None:
        boxes.append((far, -30.0, far + THICK, 30.0))
    assert find(scan(boxes)) is None
    assert find(scan(boxes, noise=0.01, nan_rate=0.01, inf_rate=0.02, seed=1)) is None


def test_a_gap_between_the_wall_and_an_obstacle_in_front_is_no_window():
    boxes = wall(2.0, [(-8.0, -1.0)], far=8.0) + [(1.0, 1.0, 1.3, 3.0)]
    assert find(scan(boxes)) is None


@pytest.mark.parametrize('gaps,width', [([], 2.0), ([(-0.4, 0.4)], 2.0), ([(-1.25, 1.25)], 2.0),
                                        ([(-2.0, 2.0)], 2.5)])
def test_no_opening_of_plausible_width(gaps, width):
    """A solid wall, a gap too narrow, a door when looking for a window, a gap too wide: nothing."""
    assert find(scan(wall(1.2, with_gaps(gaps), far=7.0)), width=width) is None


def test_unusable_scans():
    assert find(np.full(720, np.nan)) is None
    assert find(np.full(720, np.inf)) is None
    assert find([]) is None
    assert find_opening(np.ones(720), math.nan, INC, 2.0) is None
    assert find_opening(np.ones(720), ANGLE_MIN, 0.0, 2.0) is None


def test_two_windows():
    r = scan(wall(2.0, with_gaps([(-3.5, -1.5), (1.0, 3.0)]), far=9.0))
    both = find_openings(r, ANGLE_MIN, INC, 2.0)
    assert [round(o.lateral, 1) for o in both] == [-2.5, 2.0]
    assert abs(find(r, expected_lateral=1.5).lateral - 2.0) < 0.05
    assert abs(find(r, expected_lateral=-1.0).lateral + 2.5) < 0.05


def test_side_clearances_in_the_window():
    """Between the jambs (x from -0.1 to 0.1 around the robot), 0.3 m right of the middle."""
    boxes = [(-0.1, -8.0, 0.1, -1.0 + 0.3), (-0.1, 1.0 + 0.3, 0.1, 8.0)]
    left, right = side_clearances(scan(boxes), ANGLE_MIN, INC)
    assert abs(left - 1.3) < 0.02 and abs(right - 0.7) < 0.02


def test_passage_control():
    ctl = OpeningPassage(standoff=1.0, gain=1.0, lateral_vmax=0.4, speed=0.4, tolerance=0.12)
    v = ctl.centring(0.3, 1.5)
    assert v[0] == 0.0 and abs(v[1] - 0.3) < 1e-9                    # sideways only, never forward
    v = ctl.centring(0.0, 0.6)
    assert v[0] < 0 and v[1] == 0.0                                    # too near the wall: backs off
    assert np.linalg.norm(ctl.centring(3.0, 0.2)) <= 0.4 + 1e-9
    assert ctl.centred(0.1, 1.0) and not ctl.centred(0.2, 1.0) and not ctl.centred(0.0, 0.5)
    assert list(ctl.through(None)) == [0.4, 0.0]
    v = ctl.through(0.2)
    assert v[0] == 0.4 and abs(v[1] - 0.2) < 1e-9
    v = ctl.through(-0.5)                                              # far off the middle: stop, re-centre
    assert v[0] == 0.0 and v[1] == -0.4
    assert ctl.through(0.3)[0] == 0.0                                  # off more than twice the tolerance
    assert ctl.through(0.3, room=0.4)[0] == 0.4                        # but within the opening's room
    assert ctl.through(0.45, room=0.4)[0] == 0.0
    assert ctl.through(0.2, room=0.1)[0] == 0.0                        # a narrow opening: the frame at its edge
    assert ctl.through(0.05, room=0.1)[0] == 0.4
    assert ctl.through(0.05, room=0.1, speed=0.8)[0] == 0.8            # the crossing's own speed
    assert ctl.through(0.2, room=float('nan'))[0] == 0.4


def test_a_side_wall_beside_the_robot_is_not_the_wall_ahead():
    """Inside a room, a wall 0.8 m to the left along the heading (its returns crowd at short x) and the
    window's wall 1.5 m ahead."""
    boxes = wall(1.5, with_gaps([(-1.2, 0.8)])) + [(-3.0, 0.8, 1.5, 1.0)]
    o = find(scan(boxes, noise=0.01, nan_rate=0.01, inf_rate=0.02, seed=2))
    assert o is not None and abs(o.lateral + 0.2) < 0.05 and abs(o.distance - 1.5) < 0.05


def test_a_corridor_is_no_doorway_across_it():
    """In a corridor 2.7 m wide (side walls 1.35 m either side, along the heading, its end 2.5 m ahead): the
    side walls' returns at the same short x are no wall across it with a 2.7 m doorway 0.4 m ahead
    (c3_floor_plan_b, realistic seed 101 at rtf 4: a UAV centred 16 s on that doorway and hit the end wall).
    The end wall is the wall ahead, and it has no opening."""
    boxes = [(-3.0, 1.35, 3.0, 1.55), (-3.0, -1.55, 3.0, -1.35), (2.5, -1.55, 2.7, 1.55)]
    r = scan(boxes, noise=0.01, nan_rate=0.01, inf_rate=0.02, seed=5)
    assert find_openings(r, ANGLE_MIN, INC, 2.0, tolerance=0.9) == []
    # with a doorway 2 m wide in the end wall: that one is found, at the end wall's distance
    boxes = boxes[:2] + [(2.5, -1.55, 2.7, -1.0), (2.5, 1.0, 2.7, 1.55)]
    o = find(scan(boxes, noise=0.01, seed=6))
    assert o is not None and abs(o.distance - 2.5) < 0.1 and abs(o.lateral) < 0.1, o
