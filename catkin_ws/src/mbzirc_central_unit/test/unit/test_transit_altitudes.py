"""The UAVs' transit altitudes leave room for two reported heights held off (realistic seed 108)."""
from mbzirc_arena import c3

from mbzirc_central_unit import constants as C
from mbzirc_central_unit.bookkeeping import Bookkeeping
from mbzirc_central_unit.command import StrategyParams
from mbzirc_central_unit.transit import Router

# mbzirc_agents' defaults: a hovering UAV's box reaches 1 m above and below it (~hold_half_size), grown by
# 0.5 m for the error of its reported height (~pose_error_margin_z)
BOX_REACH_Z = 1.0 + 0.5
# how far the height a UAV holds reads off its transit altitude: a take-off goes ~altitude above the
# reported height of the pad, which reads off by the vertical GNSS bias (seed 108: UAV 1 at 4.5 after a
# take-off to 4 m, UAV 2 at 7.3 after one to 7.5)
HELD_OFF = 0.5


def test_neighbouring_transit_altitudes_keep_the_hold_boxes_apart_with_both_heights_held_off():
    router = Router(StrategyParams(), Bookkeeping(StrategyParams()))
    alts = sorted(router.altitude(a) for a in ('1', '2', '3'))
    for low, high in zip(alts, alts[1:]):
        # the lower UAV reads 0.5 m high, the upper one 0.5 m low: their boxes must still not overlap
        assert (low + HELD_OFF) + BOX_REACH_Z <= (high - HELD_OFF) - BOX_REACH_Z, (low, high)
    # an id beyond the defaults follows the same step
    assert router.altitude('4') - router.altitude('3') >= 2 * (BOX_REACH_Z + HELD_OFF)


def test_the_highest_transit_altitude_stays_under_the_flying_ceiling_and_below_the_tower_walls():
    router = Router(StrategyParams(), Bookkeeping(StrategyParams()))
    top = max(router.altitude(a) for a in ('1', '2', '3'))
    assert top + HELD_OFF + BOX_REACH_Z < c3.ARENA.bounds[5]
    # routes at the transit altitudes go around the tower (walls to 15 m): never over its roof
    assert top + HELD_OFF + BOX_REACH_Z < c3.TOWER_BOX[5]
