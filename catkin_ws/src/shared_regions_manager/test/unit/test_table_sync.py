"""TableSync: what /regions shows is the table on disk, numbered; removals are logged before the save.

The fault suite once reported 2/go_to lost by a respawned manager: its last /regions before the kill still
had the box, freed by UAV 2 and saved just before the kill. These tests replay that interleaving."""
import sys
import threading

from shared_regions_manager.core import RegionManager
from shared_regions_manager.table_sync import TableSync

BOX = {'1/parked': ((0, 0, 0), (1, 1, 1)), '2/hold': ((5, 0, 0), (6, 1, 1)), '2/go_to': ((5, 3, 0), (6, 4, 1)),
       '3/hold': ((10, 0, 0), (11, 1, 1)), '3/go_to': ((10, 3, 0), (11, 4, 1))}


class Recorder:
    """The node's side: a disk that keeps the last saved table, a /regions stream and a log, each event
    also appended to one timeline."""

    def __init__(self):
        self.disk = None                 # (table, keys)
        self.shown = []                  # (table, keys, disk at that moment)
        self.log = []
        self.timeline = []

    def save(self, state, table):
        keys = frozenset(f"{d['agent']}/{d['label']}" for d in state['regions'])
        self.disk = (table, keys)
        self.timeline.append(('save', table, keys))

    def publish(self, regions, table):
        keys = frozenset(f'{a}/{l}' for a, l in regions)
        self.shown.append((table, keys, self.disk))
        self.timeline.append(('publish', table, keys))

    def write_log(self, text):
        self.log.append(text)
        self.timeline.append(('log', text))


def table_of_the_run():
    core = RegionManager(known_agents=['0', '1', '2', '3'])
    rec = Recorder()
    sync = TableSync(core, rec.save, rec.publish, rec.write_log)
    for name in ('1/parked', '2/hold', '2/go_to', '3/go_to', '3/hold'):
        agent, label = name.split('/')
        assert sync.change(lambda: core.ask(agent, label, *BOX[name]))[0]
    return core, rec, sync


def test_every_change_is_numbered_saved_then_shown_and_a_refusal_changes_nothing():
    core, rec, sync = table_of_the_run()
    assert sync.table == 5 and rec.disk[0] == 5
    assert [e[:2] for e in rec.timeline] == [(k, t) for t in range(1, 6) for k in ('save', 'publish')]
    assert not sync.change(lambda: core.ask('3', 'x', *BOX['2/hold']))[0]      # overlaps: refused
    assert not sync.change(lambda: core.free('1', 'nothing'))[0]
    assert sync.table == 5 and len(rec.timeline) == 10
    sync.republish()                                                              # the timer
    assert rec.shown[-1][:2] == (5, rec.disk[1])


def test_a_free_is_logged_before_its_save_and_shown_after_it():
    core, rec, sync = table_of_the_run()
    del rec.timeline[:]
    assert sync.change(lambda: core.free('2', 'go_to', caller='/mbzirc2020_2/agent'))[0]
    assert [e[0] for e in rec.timeline] == ['log', 'save', 'publish']
    assert rec.log == ['region manager: table 6: removed 2/go_to']
    assert rec.shown[-1][:2] == (6, frozenset({'1/parked', '2/hold', '3/go_to', '3/hold'}))


def test_the_timer_never_shows_a_table_read_before_a_free_after_the_free():
    """The run's interleaving: the timer reads the table (2/go_to still held), UAV 2 frees 2/go_to (saved and
    shown), then the timer publishes. With the old node the timer's stale table came last on /regions; now
    the free waits for the timer's publication, and /regions ends with the table on disk."""
    core, rec, sync = table_of_the_run()
    timer_read = threading.Event()
    real_regions = core.regions
    outcome = {}

    def regions_then_let_the_free_run():
        out = real_regions()
        if threading.current_thread().name == 'timer' and not timer_read.is_set():
            timer_read.set()
            # the free runs now, between the timer's read and its publication; it must not get through
            # before the timer published (it would have with the old node: no common lock)
            freer = threading.Thread(target=lambda: outcome.setdefault(
                'free', sync.change(lambda: core.free('2', 'go_to', caller='/mbzirc2020_2/agent'))))
            freer.start()
            outcome['freer'] = freer
        return out

    core.regions = regions_then_let_the_free_run
    timer = threading.Thread(target=sync.republish, name='timer')
    timer.start()
    timer.join()
    outcome['freer'].join()
    core.regions = real_regions
    assert outcome['free'][0]
    last_table, last_keys, disk = rec.shown[-1]
    assert '2/go_to' not in last_keys and (last_table, last_keys) == disk
    tables = [t for t, _, _ in rec.shown]
    assert tables == sorted(tables), 'table numbers went back on /regions'


def test_under_concurrent_requests_each_publication_is_the_table_on_disk():
    core = RegionManager(known_agents=['1', '2', '3'])
    rec = Recorder()
    sync = TableSync(core, rec.save, rec.publish, rec.write_log)
    names = list(BOX)
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)                  # switch threads as often as possible
    try:
        def agent(i):
            for k in range(300):
                name = names[(i + k) % len(names)]
                a, label = name.split('/')
                if k % 3 == 2:
                    sync.change(lambda: core.free(a, label))
                else:
                    sync.change(lambda: core.ask(a, label, *BOX[name]))
                if k % 7 == 0:
                    sync.republish()
        threads = [threading.Thread(target=agent, args=(i,)) for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(old)
    assert rec.shown
    for table, keys, disk in rec.shown:
        assert (table, keys) == disk
    tables = [t for t, _, _ in rec.shown]
    assert tables == sorted(tables)


def test_removals_between_a_shown_table_and_the_saved_one_are_in_the_log():
    """What the fault suite relies on: a box of a shown table missing from the table on disk was logged as
    removed by a later table."""
    core, rec, sync = table_of_the_run()
    shown_table, shown_keys, _ = rec.shown[-1]
    sync.change(lambda: core.free('2', 'go_to'))
    sync.change(lambda: core.ask('1', 'go_to', (0, 3, 0), (1, 4, 1)))
    sync.change(lambda: core.free('3', '', free_all=True))
    saved_table, saved_keys = rec.disk
    logged = set()
    for line in rec.log:
        n, keys = line.split('table ')[1].split(': removed ')
        if shown_table < int(n) <= saved_table:
            logged |= set(keys.split(', '))
    assert shown_keys - saved_keys == logged == {'2/go_to', '3/hold', '3/go_to'}
