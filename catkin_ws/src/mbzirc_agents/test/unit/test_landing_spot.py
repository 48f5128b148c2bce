"""landing_spot: where a UAV aims its landing at home, away from the other UAVs' pads (pure)."""
import itertools
import math

from mbzirc_arena.c3 import ARENA
from mbzirc_agents.tasks.uav_motion import landing_spot, other_uav_homes


def _spots(offset):
    return {h.robot_id: landing_spot(h.position, other_uav_homes(h.robot_id), offset)
            for h in ARENA.homes if h.kind == 'uav'}


def test_the_arena_pads_landing_spots_are_further_apart_than_the_pads():
    """The pads of UAVs 1-3 are 2.59-3.3 m apart; aimed 0.5 m off them, away from the others, the aimed
    points are >= 3.4 m apart: two neighbours with ~0.7 m of GNSS error each then stay >= 2 m apart."""
    pads = {h.robot_id: h.position for h in ARENA.homes if h.kind == 'uav'}
    spots = _spots(0.5)
    for a, b in itertools.combinations(sorted(spots), 2):
        assert math.dist(spots[a], spots[b]) >= 3.4, (a, b, spots)
        assert math.dist(spots[a], spots[b]) > math.dist(pads[a][:2], pads[b][:2]) + 0.8
    for rid, s in spots.items():
        assert math.isclose(math.dist(s, pads[rid][:2]), 0.5, abs_tol=1e-9)


def test_pad_1_between_two_pads_to_its_east_lands_to_the_west():
    x, y = landing_spot((-2.0, 1.65, 0.0), [(0.0, 0.0, 0.0), (0.0, 3.3, 0.0)], 0.5)
    assert math.isclose(x, -2.5) and math.isclose(y, 1.65)


def test_no_offset_no_neighbour_or_a_balanced_pad_lands_on_the_centre():
    assert landing_spot((1.0, 2.0), [(5.0, 2.0)], 0.0) == (1.0, 2.0)
    assert landing_spot((1.0, 2.0), [], 0.5) == (1.0, 2.0)
    assert landing_spot((0.0, 0.0), [(2.0, 0.0), (-2.0, 0.0)], 0.5) == (0.0, 0.0)
