"""Shared-region manager: two agents never hold overlapping boxes."""
import random
import threading

from mbzirc_arena.boxes import boxes_overlap
from mbzirc_ros_utils import state_file
from shared_regions_manager.core import RegionManager


def test_overlapping_request_of_another_agent_is_refused():
    rm = RegionManager()
    assert rm.ask('1', 'go_to', (0, 0, 0), (5, 5, 5))[0]
    ok, why = rm.ask('2', 'go_to', (4, 4, 4), (8, 8, 8))
    assert not ok and '1' in why
    assert rm.ask('2', 'go_to', (6, 6, 6), (8, 8, 8))[0]


def test_own_overlap_allowed_and_label_replaced():
    rm = RegionManager()
    assert rm.ask('1', 'a', (0, 0, 0), (5, 5, 5))[0]
    assert rm.ask('1', 'b', (1, 1, 1), (6, 6, 6))[0]
    assert rm.ask('1', 'a', (20, 20, 0), (21, 21, 1))[0]      # replaces 'a'
    assert len(rm.regions()) == 2
    assert rm.ask('2', 'x', (0, 0, 0), (0.9, 0.9, 0.9))[0]    # old 'a' is gone


def test_free_label_and_all():
    rm = RegionManager()
    rm.ask('1', 'a', (0, 0, 0), (1, 1, 1))
    rm.ask('1', 'b', (2, 2, 2), (3, 3, 3))
    assert not rm.ask('2', 'c', (0, 0, 0), (1, 1, 1))[0]
    assert rm.free('1', 'a')[0]
    assert rm.ask('2', 'c', (0, 0, 0), (1, 1, 1))[0]
    assert not rm.free('1', 'nope')[0]
    assert rm.free('1', free_all=True)[0]
    assert rm.owner_at((2.5, 2.5, 2.5)) is None


def test_nan_box_refused():
    assert not RegionManager().ask('1', 'a', (float('nan'), 0, 0), (1, 1, 1))[0]


def test_concurrent_random_requests_never_overlap():
    rm = RegionManager()
    rng = random.Random(3)

    def worker(agent):
        for i in range(300):
            x, y, z = rng.uniform(0, 20), rng.uniform(0, 20), rng.uniform(0, 10)
            rm.ask(agent, f'r{i % 3}', (x, y, z), (x + 3, y + 3, z + 3))
            if i % 7 == 0:
                rm.free(agent, f'r{i % 3}')

    threads = [threading.Thread(target=worker, args=(a,)) for a in ('1', '2', '3')]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    regions = list(rm.regions().items())
    for i, ((oa, _), ba) in enumerate(regions):
        for (ob, _), bb in regions[i + 1:]:
            if oa != ob:
                assert not boxes_overlap(ba, bb)


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_only_the_owner_its_namespace_or_a_supervisor_frees():
    rm = RegionManager(known_agents=['1', '2'])
    assert rm.ask('1', 'a', (0, 0, 0), (1, 1, 1), caller='/mbzirc2020_1/agent')[0]
    ok, why = rm.free('1', free_all=True, caller='/mbzirc2020_2/agent')     # another robot: refused
    assert not ok and 'may not free' in why and rm.owner_at((0.5, 0.5, 0.5)) == '1'
    assert not rm.free('1', 'a', caller='/fuzzer')[0]
    assert rm.free('1', 'a', caller='/mbzirc2020_1/agent')[0]                # the owner
    rm.ask('1', 'a', (0, 0, 0), (1, 1, 1), caller='/mbzirc2020_1/agent')
    assert rm.free('1', free_all=True, caller='/mbzirc2020_1/other_node')[0]  # its namespace (respawned)
    rm.ask('1', 'a', (0, 0, 0), (1, 1, 1), caller='/mbzirc2020_1/agent')
    assert rm.free('1', free_all=True, caller='/central_unit')[0]           # supervisor: a crashed robot
    rm.ask('x', 'a', (0, 0, 0), (1, 1, 1), caller='/tool')
    assert rm.free('x', 'a', caller='/tool')[0]                               # the node that reserved it


def test_ghost_reservation_of_the_whole_arena_expires():
    clock = Clock()
    rm = RegionManager(known_agents=['1', '2', '3'], unknown_lease_s=10.0, clock=clock)
    assert rm.ask('ghost', 'all', (-100, -100, -10), (100, 100, 100), caller='/stale_tool')[0]
    assert not rm.ask('1', 'go_to', (0, 0, 0), (5, 5, 5))[0]
    clock.t = 9.0
    assert not rm.ask('1', 'go_to', (0, 0, 0), (5, 5, 5))[0]
    clock.t = 10.5                                    # no renewal: lease over
    assert rm.ask('1', 'go_to', (0, 0, 0), (5, 5, 5))[0]
    clock.t = 1000.0                                  # a robot's boxes never expire by time
    assert rm.expire() == [] and rm.owner_at((1, 1, 1)) == '1'


def test_renewed_ghost_keeps_its_lease():
    clock = Clock()
    rm = RegionManager(known_agents=['1'], unknown_lease_s=10.0, clock=clock)
    for t in (0.0, 8.0, 16.0):
        clock.t = t
        assert rm.ask('ghost', 'a', (0, 0, 0), (1, 1, 1))[0]
    clock.t = 20.0
    assert rm.expire() == []
    clock.t = 26.5
    assert rm.expire() == [('ghost', 'a')]


def test_table_is_bounded():
    rm = RegionManager(max_labels_per_agent=3, max_agents=2)
    for i in range(3):
        assert rm.ask('1', f'l{i}', (i * 10, 0, 0), (i * 10 + 1, 1, 1))[0]
    ok, why = rm.ask('1', 'l3', (50, 0, 0), (51, 1, 1))
    assert not ok and 'max 3' in why
    assert rm.ask('1', 'l0', (60, 0, 0), (61, 1, 1))[0]            # replacing a label is fine
    assert rm.ask('2', 'a', (70, 0, 0), (71, 1, 1))[0]
    ok, why = rm.ask('3', 'a', (80, 0, 0), (81, 1, 1))
    assert not ok and 'agents' in why
    assert len(rm.regions()) == 4


def test_state_round_trip_through_the_state_file(tmp_path):
    rm = RegionManager(known_agents=['1', '2'])
    rm.ask('1', 'a', (0, 0, 0), (1, 1, 1), caller='/mbzirc2020_1/agent')
    rm.ask('2', 'parked', (5, 5, 0), (6, 6, 3), caller='/mbzirc2020_2/agent')
    path = str(tmp_path / 'regions.json')
    state_file.save(path, state_file.encode(rm.to_state(), 'fmt', 1, 'run', 5.0))
    res = state_file.load(path, 'fmt', 1, 'run', 6.0)
    again = RegionManager(known_agents=['1', '2'])
    assert again.load_state(res.state) == 2
    assert not again.ask('2', 'x', (0.5, 0.5, 0.5), (2, 2, 2))[0]          # still 1's airspace
    assert not again.free('1', 'a', caller='/mbzirc2020_2/agent')[0]       # who reserved it is kept too
    assert again.regions().keys() == rm.regions().keys()


def test_load_refuses_malformed_or_overlapping_tables():
    rm = RegionManager()
    rm.ask('1', 'a', (0, 0, 0), (1, 1, 1))
    bad = [{'regions': [{'agent': '1', 'label': 'a', 'min': [0, 0, float('nan')], 'max': [1, 1, 1]}]},
           {'regions': [{'agent': '1', 'label': 'a', 'min': [0, 0], 'max': [1, 1, 1]}]},
           {'regions': [{'agent': '1', 'label': 'a', 'min': [0, 0, 0], 'max': [2, 2, 2]},
                        {'agent': '2', 'label': 'b', 'min': [1, 1, 1], 'max': [3, 3, 3]}]},
           {'nothing': 1}]
    for state in bad:
        try:
            rm.load_state(state)
            raise AssertionError(f'accepted {state}')
        except ValueError:
            pass
    assert rm.owner_at((0.5, 0.5, 0.5)) == '1'                             # unchanged


# ---- deadlocks: a wait-for cycle between refused requests and held boxes -------------------------------------
class FakeClock:
    """Seconds that move only when the test says so."""

    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def seed_104_cycle(rm, clock, seconds=3.0):
    """Realistic seed 104 right after take-off: UAV 2 holds at z 6, UAV 3 at z 7.4, 4 m apart; each one's
    go_to (retried at 2 Hz) overlaps the other's hold."""
    assert rm.ask('2', 'hold', (-0.4, -2.0, 5.0), (1.6, 0.0, 7.0))[0]
    assert rm.ask('3', 'hold', (0.4, 2.1, 6.4), (2.4, 4.1, 8.4))[0]
    for _ in range(int(seconds * 2)):
        assert not rm.ask('3', 'go_to', (-1.0, -6.0, 6.4), (2.4, 4.1, 8.4))[0]     # 3 across 2's hold
        assert not rm.ask('2', 'go_to', (-0.4, -2.0, 5.0), (4.0, 9.0, 7.0))[0]     # 2 across 3's hold
        clock.t += 0.5


def test_two_agent_cycle_names_the_lower_priority_agent_to_step_out_of_the_others_box():
    clock = FakeClock()
    rm = RegionManager(known_agents=['0', '1', '2', '3'], clock=clock)
    seed_104_cycle(rm, clock)
    order = rm.deadlock()
    assert order is not None, 'the two-agent cycle was not found'
    assert (order.victim, order.winner, order.winner_label, order.victim_labels) == ('3', '2', 'go_to', ('hold',))
    assert list(order.box[0]) == [-0.4, -2.0, 5.0] and list(order.box[1]) == [4.0, 9.0, 7.0]
    words = order.describe()
    assert '2/go_to' in words and '3/hold' in words and '3/go_to' in words and '2/hold' in words
    assert rm.deadlock() is None                          # not repeated while the victim steps aside
    # 3 steps up out of 2's go_to box: 2's request is granted, the cycle is gone
    assert rm.ask('3', 'hold', (0.4, 2.1, 7.1), (2.4, 4.1, 9.1))[0]
    assert rm.ask('2', 'go_to', (-0.4, -2.0, 5.0), (4.0, 9.0, 7.0))[0]
    clock.t += 30.0
    assert rm.deadlock() is None


def test_no_deadlock_for_a_one_way_wait_a_short_one_or_an_agent_that_stopped_asking():
    clock = FakeClock()
    rm = RegionManager(known_agents=['2', '3'], clock=clock, deadlock_after_s=2.0)
    assert rm.ask('2', 'hold', (0, 0, 0), (2, 2, 2))[0]
    assert rm.ask('3', 'hold', (10, 0, 0), (12, 2, 2))[0]
    for _ in range(10):                                   # 3 waits for 2, 2 waits for nobody
        assert not rm.ask('3', 'go_to', (1, 0, 0), (11, 2, 2))[0]
        clock.t += 0.5
    assert rm.deadlock() is None
    rm2 = RegionManager(known_agents=['2', '3'], clock=clock, deadlock_after_s=2.0)
    seed_104_cycle(rm2, clock, seconds=1.0)              # a cycle of 1 s: not yet
    assert rm2.deadlock() is None
    clock.t += 5.0                                        # both stopped asking (preempted): nobody waits
    assert rm2.deadlock() is None


def test_a_declined_order_names_the_next_agent_of_the_cycle_and_orders_are_retried_later():
    clock = FakeClock()
    rm = RegionManager(known_agents=['0', '1', '2', '3'], clock=clock, yield_retry_s=20.0)
    seed_104_cycle(rm, clock)
    first = rm.deadlock()
    rm.yield_answer(first, accepted=False)
    seed_104_cycle(rm, clock, seconds=1.0)
    second = rm.deadlock()
    assert (first.victim, second.victim, second.winner) == ('3', '2', '3')
    rm.yield_answer(second, accepted=False)
    seed_104_cycle(rm, clock, seconds=1.0)
    assert rm.deadlock() is None                          # both declined: wait before asking again
    seed_104_cycle(rm, clock, seconds=20.0)
    assert rm.deadlock().victim == '3'


def test_priority_param_and_three_agent_cycle():
    clock = FakeClock()
    rm = RegionManager(known_agents=['1', '2', '3'], priority=['3', '1', '2'], clock=clock)
    for a, x in (('1', 0), ('2', 10), ('3', 20)):
        assert rm.ask(a, 'hold', (x, 0, 0), (x + 2, 2, 2))[0]
    for _ in range(6):                                    # 1 -> 2 -> 3 -> 1
        assert not rm.ask('1', 'go_to', (1, 0, 0), (11, 2, 2))[0]
        assert not rm.ask('2', 'go_to', (11, 0, 0), (21, 2, 2))[0]
        assert not rm.ask('3', 'go_to', (1, 0, 0), (21, 2, 0.5))[0]   # overlaps 1 and 2: 2 is not its wait
        clock.t += 0.5
    order = rm.deadlock()
    assert order is not None and order.victim == '2' and order.winner == '1'
    assert [w.agent for w in order.cycle] == ['1', '2', '3']


def test_unknown_agents_never_take_part_in_a_deadlock():
    clock = FakeClock()
    rm = RegionManager(known_agents=['2'], clock=clock)
    assert rm.ask('2', 'hold', (0, 0, 0), (2, 2, 2))[0]
    assert rm.ask('ghost', 'hold', (10, 0, 0), (12, 2, 2))[0]
    for _ in range(6):
        rm.ask('2', 'go_to', (1, 0, 0), (11, 2, 2))
        rm.ask('ghost', 'go_to', (1, 0, 0), (11, 2, 2))
        clock.t += 0.5
    assert rm.deadlock() is None


def test_an_order_accepted_but_not_carried_out_names_the_other_agent_next():
    """Realistic seed 108: the victim (UAV 2) accepted every order but found no step granted, and the cycle
    stood 360 s; the manager asked UAV 2 again every yield_retry and never UAV 1, which could have moved.
    When the same cycle still stands after an accepted order's yield_retry, the robot asked fewer times is
    named next (ties: the lower priority)."""
    clock = FakeClock()
    rm = RegionManager(known_agents=['0', '1', '2', '3'], clock=clock, yield_retry_s=20.0)
    seed_104_cycle(rm, clock)
    first = rm.deadlock()
    rm.yield_answer(first, accepted=True)                  # accepted, then no step granted: nothing moved
    seed_104_cycle(rm, clock, seconds=20.0)
    second = rm.deadlock()
    assert (first.victim, second.victim, second.winner) == ('3', '2', '3')
    rm.yield_answer(second, accepted=True)
    seed_104_cycle(rm, clock, seconds=20.0)
    assert rm.deadlock().victim == '3'                     # each asked once: the lower priority again
    # a cycle standing again long after the last order starts from the priority again
    rm2 = RegionManager(known_agents=['2', '3'], clock=clock, yield_retry_s=20.0)
    seed_104_cycle(rm2, clock)
    rm2.yield_answer(rm2.deadlock(), accepted=True)
    clock.t += 200.0
    seed_104_cycle(rm2, clock)
    assert rm2.deadlock().victim == '3'


def test_a_long_wait_for_a_robot_that_waits_for_nothing_asks_that_robot_to_leave():
    """No cycle: UAV 2 hovers with no work (holds its hold box, asks for nothing) on UAV 1's way. After
    idle_yield_after of UAV 1's wait, UAV 2 is asked to leave UAV 1's box; not before, not an unknown agent,
    and not again within yield_retry."""
    clock = FakeClock()
    rm = RegionManager(known_agents=['1', '2'], clock=clock, idle_yield_after_s=15.0, yield_retry_s=20.0)
    assert rm.ask('2', 'hold', (-1, -1, 5.8), (1, 1, 8.8))[0]
    assert rm.ask('ghost', 'hold', (-8, 2, 3), (-6, 4, 5))[0]
    went = []
    for _ in range(40):                                    # 20 s of UAV 1 asking at 2 Hz
        assert not rm.ask('1', 'go_to', (-11.5, 0.6, 2.5), (-0.3, 9.6, 5.9))[0]
        order = rm.deadlock()
        if order is not None:
            went.append((clock.t - 100.0, order))
        clock.t += 0.5
    assert len(went) == 1, [(t, o.describe()) for t, o in went]
    t, order = went[0]
    assert 15.0 <= t <= 16.0
    assert (order.victim, order.winner, order.winner_label, order.victim_labels) == ('2', '1', 'go_to', ('hold',))
    assert 'waited 15 s for 2/hold, and 2 waits for nothing' in order.describe()
