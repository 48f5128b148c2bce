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
