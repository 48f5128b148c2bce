"""Object estimator persistence: state round trip, atomic file, corrupt / foreign / stale files."""
import json
import os

import numpy as np
import pytest

from mbzirc_arena import messages as C
from object_estimation import store
from object_estimation.core import Detection, ObjectEstimator


def det(p, t=0.0, agent='1', typ=C.TYPE_FIRE):
    return Detection(type=typ, position=np.array(p, float), covariance=np.diag([1.5 ** 2, 1.5 ** 2, 0.25]),
                     stamp=t, agent_id=agent)


def estimator_with_tracks():
    """Two confirmed fires (one EXTINGUISHED), one hole, one tentative fire."""
    est = ObjectEstimator(min_updates=3)
    for k in range(4):
        est.add(det((10, 20, 5), t=k, agent='2'))
        est.add(det((0, 0, 0), t=k, agent='1'))
        est.add(det((5, 5, 1), t=k, typ=C.TYPE_HOLE, agent='3'))
    est.add(det((30, 30, 0), t=4.0))
    assert est.set_status(2, C.STATUS_EXTINGUISHED) == ''
    return est


def test_round_trip_keeps_ids_statuses_and_estimates(tmp_path):
    est = estimator_with_tracks()
    path = str(tmp_path / 'tracks.json')
    store.save(path, store.encode(est.to_state(), 'run-a', saved_at=12.5))
    res = store.load(path, 'run-a', now=14.0)
    assert res.kind == store.OK, res.reason
    again = ObjectEstimator(min_updates=3)
    again.load_state(res.state)
    assert sorted(again.tracks) == sorted(est.tracks)
    for tid, t in est.tracks.items():
        r = again.tracks[tid]
        assert (r.type, r.status, r.num_updates, r.sub_type, r.agents) == \
            (t.type, t.status, t.num_updates, t.sub_type, t.agents)
        assert np.allclose(r.position, t.position) and np.allclose(r.covariance, t.covariance)
        assert (r.first_seen, r.last_update) == (t.first_seen, t.last_update)
    assert again.tracks[2].status == C.STATUS_EXTINGUISHED
    assert [o.id for o in again.objects()] == [o.id for o in est.objects()]
    # ids continue: a new object gets the next id, never one in use; old objects still associate
    assert again.add(det((0, 0, 0), t=5.0)).id == 2
    new = again.add(det((-40, 40, 0), t=5.0))
    assert new.id == est.next_id and new.id not in est.tracks


def test_next_id_stays_ahead_of_restored_ids():
    est = estimator_with_tracks()
    state = est.to_state()
    state['next_id'] = 1                      # an older writer's counter: must not reuse track ids
    again = ObjectEstimator()
    again.load_state(state)
    assert again.next_id == max(est.tracks) + 1


def test_atomic_save_leaves_no_temporary_and_replaces(tmp_path):
    path = str(tmp_path / 'sub' / 'tracks.json')
    store.save(path, 'first')
    store.save(path, 'second')
    assert open(path).read() == 'second'
    assert os.listdir(tmp_path / 'sub') == ['tracks.json']


def test_failed_save_keeps_previous_file(tmp_path, monkeypatch):
    path = str(tmp_path / 'tracks.json')
    store.save(path, 'good')

    def boom(*_a):
        raise OSError('disk full')
    monkeypatch.setattr(os, 'replace', boom)
    with pytest.raises(OSError):
        store.save(path, 'half')
    assert open(path).read() == 'good'
    assert os.listdir(tmp_path) == ['tracks.json']


def test_missing_file(tmp_path):
    assert store.load(str(tmp_path / 'none.json'), 'run-a', 1.0).kind == store.MISSING


@pytest.mark.parametrize('text', ['{"format": "mbzirc_agents/estimator_tracks", "version": 1, "saved_at": 1, "tr',
                                  '', '\x00\x01garbage', '[1, 2, 3]', '{"tracks": []}',
                                  json.dumps({'format': store.FORMAT, 'version': 99, 'saved_at': 1, 'tracks': []}),
                                  json.dumps({'format': store.FORMAT, 'version': 1, 'saved_at': 'x', 'tracks': []}),
                                  json.dumps({'format': store.FORMAT, 'version': 1, 'saved_at': 1, 'tracks': 5})])
def test_corrupt_or_foreign_file_is_invalid(tmp_path, text):
    path = tmp_path / 'tracks.json'
    path.write_text(text)
    res = store.load(str(path), 'run-a', 5.0)
    assert res.kind == store.INVALID and str(path) in res.reason


@pytest.mark.parametrize('mutate', [
    lambda s: s['tracks'][0].update(position=[float('nan'), 0, 0]),
    lambda s: s['tracks'][0].update(covariance=[[1, 0, 0], [0, -1, 0], [0, 0, 1]]),
    lambda s: s['tracks'][0].update(covariance=[1, 2]),
    lambda s: s['tracks'][0].update(status=17),
    lambda s: s['tracks'][0].pop('type'),
    lambda s: s['tracks'][1].update(id=s['tracks'][0]['id']),
    lambda s: s['tracks'][0].update(id=0),
    lambda s: s.update(next_id='many'),
    lambda s: s['tracks'].append('not a track'),
])
def test_malformed_tracks_rejected_whole_and_estimator_unchanged(mutate):
    state = json.loads(json.dumps(estimator_with_tracks().to_state()))
    mutate(state)
    est = ObjectEstimator()
    est.add(det((1, 1, 1)))
    with pytest.raises(ValueError):
        est.load_state(state)
    assert list(est.tracks) == [1] and est.next_id == 2


def test_stale_files_are_ignored(tmp_path):
    path = str(tmp_path / 'tracks.json')
    store.save(path, store.encode(estimator_with_tracks().to_state(), 'run-a', saved_at=500.0))
    assert store.load(path, 'run-b', now=600.0).kind == store.STALE           # another master / mission
    res = store.load(path, 'run-a', now=20.0)                                  # clock restarted: earlier sim
    assert res.kind == store.STALE and 'later than now' in res.reason
    assert store.load(path, '', now=20.0).kind == store.STALE
    assert store.load(path, 'run-a', now=500.5).kind == store.OK               # same mission, just after
    assert store.load(path, '', now=0.0).kind == store.OK                      # nothing to judge by


def test_state_without_tentative_tracks_keeps_every_published_one():
    est = estimator_with_tracks()
    state = est.to_state(include_tentative=False)
    assert {d['id'] for d in state['tracks']} == {t.id for t in est.objects()}
    assert len(state['tracks']) < len(est.to_state()['tracks'])        # the tentative fire is not written
    assert state['next_id'] == est.next_id
