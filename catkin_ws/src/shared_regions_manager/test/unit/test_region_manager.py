"""Shared-region manager: two agents never hold overlapping boxes."""
import random
import threading

from mbzirc_agents.geometry import boxes_overlap
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
    assert rm.free('1', 'a')
    assert rm.ask('2', 'c', (0, 0, 0), (1, 1, 1))[0]
    assert not rm.free('1', 'nope')
    assert rm.free('1', free_all=True)
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
