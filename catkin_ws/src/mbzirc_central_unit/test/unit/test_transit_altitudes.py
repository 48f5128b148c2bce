"""The UAVs' transit altitudes leave room for two reported heights held off (realistic seed 108)."""
from mbzirc_arena import c3

from mbzirc_central_unit import constants as C
from mbzirc_central_unit.bookkeeping import Bookkeeping
from mbzirc_central_unit.command import Command, StrategyParams
from mbzirc_central_unit.transit import Router
from mbzirc_central_unit.world_model import AgentView

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



def _uav(agent_id: str, landed: bool) -> AgentView:
    return AgentView(agent_id, C.ROBOT_UAV, C.PAYLOAD_BLANKET, -2.0, 1.65, 0.0 if landed else 4.0,
                     C.UAL_LANDED_DISARMED if landed else C.UAL_FLYING_AUTO)


def _sent_home_for_good(book: Bookkeeping, router: Router, agent_id: str, succeeded: bool = True) -> None:
    """The strategy sends a flying UAV home for good; its go-home ends (succeeded or not) on its pad."""
    cmd = router.go_home_for_good(_uav(agent_id, landed=False))
    assert cmd is not None and cmd.task == C.GO_HOME_AND_REFILL and agent_id in book.finished
    book.on_sent(cmd)
    book.record(cmd, succeeded)


def test_the_uavs_still_flying_take_the_lowest_transit_altitudes_once_one_lands_for_good():
    book = Bookkeeping(StrategyParams())
    router = Router(StrategyParams(), book)
    assert [router.altitude(a) for a in ('1', '2', '3')] == [4.0, 8.0, 12.0]
    # the blanket UAV is sent home for good: while it flies home it keeps its layer
    cmd = router.go_home_for_good(_uav('1', landed=False))
    book.on_sent(cmd)
    assert [router.altitude(a) for a in ('2', '3')] == [8.0, 12.0]
    book.record(cmd, True)
    assert router.go_home_for_good(_uav('1', landed=True)) is None     # the next decision: landed, stays
    # landed: the water UAVs move down one layer each, still one layer apart
    assert [router.altitude(a) for a in ('2', '3')] == [4.0, 8.0]
    # it flies again (a new ground fire): it takes its layer back, the others theirs
    assert router.altitude('1') == 4.0
    book.on_sent(Command('1', C.TAKE_OFF, {"height": 4.0}, "to search the ground"))
    assert [router.altitude(a) for a in ('1', '2', '3')] == [4.0, 8.0, 12.0]
    book.record(book.in_flight['1'], True)                            # flying, between two goals
    assert [router.altitude(a) for a in ('2', '3')] == [8.0, 12.0]


def test_a_uav_whose_go_home_for_good_was_preempted_on_its_pad_frees_its_layer_too():
    # realistic seed 102: the blanket UAV's go-home with no work left was preempted (heartbeat loss) on its pad
    book = Bookkeeping(StrategyParams())
    router = Router(StrategyParams(), book)
    _sent_home_for_good(book, router, '1', succeeded=False)
    assert [router.altitude(a) for a in ('2', '3')] == [8.0, 12.0]    # not seen landed yet
    assert router.go_home_for_good(_uav('1', landed=True)) is None
    assert [router.altitude(a) for a in ('2', '3')] == [4.0, 8.0]


def test_a_crashed_uav_frees_its_transit_altitude_and_a_refill_does_not():
    book = Bookkeeping(StrategyParams())
    router = Router(StrategyParams(), book)
    refill = Command('2', C.GO_HOME_AND_REFILL, {}, "refill: the tank is empty")
    book.on_sent(refill)
    book.record(refill, True)                      # landed at home for a refill: it flies again soon
    assert router.altitude('3') == 12.0
    book.crashed.add('2')
    assert [router.altitude(a) for a in ('1', '3')] == [4.0, 8.0]
