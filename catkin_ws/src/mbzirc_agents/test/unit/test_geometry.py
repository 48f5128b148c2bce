"""Geometry of the tasks: facade standoff poses, facing poses, walls ahead, lawn-mower paths (boxes, footprints
and routing are tested in mbzirc_arena)."""
import math

import numpy as np
import pytest
from mbzirc_arena.yaw import wrap_angle

from mbzirc_agents import constants as C
from mbzirc_agents import geometry as g


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


def test_facade_standoff_of_a_fire_above_the_extension_is_out_from_the_tower():
    """Facade D fire 0.7 m from the north-east corner, above the extension: out along +x, facing west.

    Seed 9, fire D_3: with the extension's edge taken as a wall there, the UAV was pushed off the hole.
    """
    pos, yaw = g.facade_standoff((24.2, 18.8, 12.5), C.BUILDINGS, 1.5)
    assert pos == pytest.approx((25.7, 18.8, 12.5)) and math.cos(yaw) == pytest.approx(-1.0)


def test_facing_pose():
    pos, yaw = g.facing_pose((0, 0, 1), (5, 0, 1), 1.5)
    assert pos == pytest.approx((1.5, 0, 1)) and abs(wrap_angle(yaw - math.pi)) < 1e-9


def test_lawnmower_covers_area():
    pts = g.lawnmower((0, 0, 10, 6), 2.0, 4.0)
    ys = sorted({p[1] for p in pts})
    assert ys[0] == 0 and ys[-1] == 6 and max(np.diff(ys)) <= 2.0
    assert all(p[2] == 4.0 for p in pts)
    assert pts[1][0] == 10 and pts[2][0] == 10      # boustrophedon: legs alternate


def test_faces_wall():
    assert g.faces_wall((12.4, 22.0, 6.5), -math.pi / 2, C.BUILDINGS)        # 2.5 m north of facade A
    assert not g.faces_wall((12.4, 22.0, 6.5), math.pi / 2, C.BUILDINGS)     # looking away
    assert not g.faces_wall((9.2, 21.7, 6.5), -math.pi / 2, C.BUILDINGS)     # corner waypoint
    assert not g.faces_wall((30.0, 21.5, 6.5), -math.pi / 2, C.BUILDINGS)    # above the extension roof
    assert g.faces_wall((30.0, 21.5, 2.0), -math.pi / 2, C.BUILDINGS)
    assert not g.faces_wall((12.4, 22.0, 6.5), None, C.BUILDINGS)


def test_a_facade_fire_estimate_snaps_to_its_known_holder():
    """Estimates carry the GNSS error (about a metre): the standoff comes from the public holder they
    belong to; an estimate far from every holder stays as it is."""
    from mbzirc_agents.tasks.facade import known_holder
    a4 = C.FACADE_HOLDERS[4]
    assert tuple(known_holder((a4[0] + 0.9, a4[1] - 0.7, a4[2] - 0.4))) == tuple(a4)
    far = (5.0, 5.0, 5.0)
    assert tuple(known_holder(far)) == far


def test_realistic_111_a_standoff_for_an_estimate_near_the_extension_corner_stands_in_the_open():
    """A_4's estimate 1.8 m into the tower (beyond the holder snap), nearer the tower's east face, which the
    extension hides below its 4.5 m roof: the standoff is on facade A, 2 m out from its plane, not inside the
    extension (before: (25.7, 17.7), refused as inside the building outline) nor 0.2 m from facade A."""
    from mbzirc_arena.buildings import in_footprint
    pos, yaw = g.facade_standoff((23.7, 17.7, 0.8), C.BUILDINGS, 2.0)
    assert pos == pytest.approx((23.7, 21.5, 0.8)) and yaw == pytest.approx(-math.pi / 2)
    assert not in_footprint(pos, C.BUILDINGS)


def test_realistic_115_the_shooting_pose_of_an_estimate_inside_the_wall_keeps_its_distance_from_the_wall():
    """Realistic seed 115: fire D_0's track at (22.97, 18.89, 5.1), 0.6 m inside facade A by the GNSS errors
    that placed it (1.9 m from D_0, beyond the holder snap): the shooting pose, 1.5 m out from the estimate, was
    0.9 m from the wall, and UAV 2 hit facade A while looking for the hole (its own GNSS error ~0.6 m). Out from
    the facade's plane it is 1.5 m from the wall whatever the estimate's error along the normal."""
    pos, _ = g.facade_standoff((22.97, 18.89, 5.1), C.BUILDINGS, 1.5)
    assert pos[1] == pytest.approx(19.5 + 1.5)
