"""HeartbeatFilter: believes the live sender, refuses replays (another mission's bag, an earlier instance,
an older seq of this one)."""
from mbzirc_ros_utils.liveness import HeartbeatFilter, new_run_id, parse_run_id


def test_run_id_round_trip():
    rid = new_run_id('central_unit', 'abc-123')
    node, mission, instance = parse_run_id(rid)
    assert (node, mission) == ('central_unit', 'abc-123') and len(instance) == 12
    assert new_run_id('central_unit', 'abc-123') != rid          # a new one per process start
    assert parse_run_id('central_unit') is None and parse_run_id('a//b') is None


def test_live_sender_and_its_restart_are_believed():
    f = HeartbeatFilter('m1')
    a, b = 'central_unit/m1/aaaa', 'central_unit/m1/bbbb'
    assert all(f.accept(a, s)[0] for s in range(1, 20))
    assert f.accept(b, 1)[0]                                       # restarted: new instance
    assert f.accept(b, 2)[0]


def test_replays_are_refused():
    f = HeartbeatFilter('m1')
    a, b = 'central_unit/m1/aaaa', 'central_unit/m1/bbbb'
    for s in range(1, 10):
        f.accept(a, s)
    ok, why = f.accept(a, 5)
    assert not ok and 'seq' in why                                  # this run's own past, replayed
    ok, why = f.accept('central_unit/m0/cccc', 100)
    assert not ok and 'another mission' in why                      # a bag of an earlier mission
    f.accept(b, 1)
    ok, why = f.accept(a, 50)
    assert not ok and 'replaced' in why                             # the dead instance's heartbeats
    assert f.refused == 3


def test_heartbeats_without_run_id_only_before_a_real_one():
    f = HeartbeatFilter('m1')
    assert f.accept('central_unit', 0)[0] and f.accept('', 0)[0]
    f.accept('central_unit/m1/aaaa', 1)
    assert not f.accept('central_unit', 0)[0]
