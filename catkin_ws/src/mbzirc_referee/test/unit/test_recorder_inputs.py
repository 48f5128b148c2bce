"""The recorder refuses a /sim/score that would corrupt the record (no ROS master: rospy's clock and log
are replaced)."""
import math
import threading
from types import SimpleNamespace

import pytest

from mbzirc_referee import recorder as R
from mbzirc_referee.summary import MissionRecord


@pytest.fixture
def rec(monkeypatch):
    errors = []
    monkeypatch.setattr(R.rospy, "get_time", lambda: 100.0)
    monkeypatch.setattr(R.rospy, "logerr_throttle", lambda _period, text: errors.append(text))
    r = R.MissionRecorder.__new__(R.MissionRecorder)          # its callbacks without its ROS set-up
    r.rec, r.lock, r.sim_start_wall, r.sim_at_start = MissionRecord(seed=0, duration=1200.0), threading.Lock(), None, 0.0
    r.errors = errors
    return r


def score(elapsed, value=0.5):
    return SimpleNamespace(elapsed=elapsed, score=value, crashed_robots=[])


@pytest.mark.parametrize("elapsed,value", [(math.nan, 0.5), (math.inf, 0.5), (1.7e308, 0.5), (50.0, math.nan),
                                           (100.0 + R.SCORE_CLOCK_SLACK_S + 1.0, 0.5)])
def test_a_score_the_clock_cannot_have_reached_or_non_finite_is_refused(rec, elapsed, value):
    rec._on_score(score(elapsed, value))
    assert rec.errors and "refused" in rec.errors[0]
    assert rec.rec.elapsed == 0.0 and rec.rec.finished() is None   # one such message used to end the trial


def test_a_valid_score_is_recorded(rec):
    rec._on_score(score(95.0, 1.5))
    assert not rec.errors and rec.rec.elapsed == 95.0 and rec.rec.score == 1.5


@pytest.mark.parametrize("text", ["1", "[]", '{"agents": 3}', '{"agents": {"1": 2}}', '{"fires": 5}', "no json"])
def test_a_status_of_the_wrong_shape_is_refused_and_the_progress_line_still_works(rec, text):
    rec.status = {"agents": {"1": {"doing": "search"}}, "fires": []}
    rec._on_status(SimpleNamespace(data=text))
    assert rec.errors
    assert "1:search" in rec.progress_line()


def test_a_valid_status_is_shown(rec):
    rec.status = {}
    rec._on_status(SimpleNamespace(data='{"agents": {"2": {"doing": "go_to"}}, "fires": [1]}'))
    assert not rec.errors and "2:go_to" in rec.progress_line() and "found 1" in rec.progress_line()
