"""Replay timeline: the frame at t is the live frame at t; seek back and forth, play, speed."""
import pytest

from mbzirc_ground_station.replay import ListSource, Replay
from mbzirc_ground_station.state import GroundStationState

from msgs import feed


def recording(n=400, dt=0.1):
    """A UAV flying along x at 1 m/s: a data_feed every dt from t = 10."""
    return [("/mbzirc2020_2/data_feed", feed("2", 0.1 * i, 0.0, 5.0), 10.0 + dt * i) for i in range(n)]


def live_frame_at(msgs, t):
    """What the live node showed at sim time t: every message received up to t folded in."""
    s = GroundStationState()
    for topic, m, mt in msgs:
        if mt <= t:
            s.apply(topic, m, mt)
    return s.frame(t, tracks=True)


@pytest.mark.parametrize("order", [[25.0, 40.0, 12.3, 45.0, 20.05], [49.9, 10.0, 30.0, 29.0, 31.0]])
def test_seek_anywhere_gives_the_live_frame(order):
    msgs = recording()
    r = Replay(ListSource(msgs), GroundStationState, checkpoint_every=5.0)
    for t in order:
        r.seek(t)
        got = r.frame(tracks=True)
        got.pop("replay")
        assert got == live_frame_at(msgs, t), t


def test_play_advances_with_speed_and_stops_at_the_end():
    msgs = recording(100)
    r = Replay(ListSource(msgs), GroundStationState)
    assert r.control({"action": "speed", "speed": 4.0}) == (True, "")
    r.control({"action": "play"})
    r.step(1.0)
    f = r.frame()
    assert f["replay"]["t"] == pytest.approx(14.0, abs=1e-6) and f["robots"][0]["pose"]["x"] == pytest.approx(4.0, abs=0.11)
    r.step(10.0)
    assert r.frame()["replay"] == {"t": 19.9, "start": 10.0, "end": 19.9, "playing": False, "speed": 4.0}
    r.control({"action": "play"})      # play at the end starts again from the beginning
    r.step(0.0)
    assert r.frame()["replay"]["t"] == pytest.approx(10.0)


def test_bad_controls_are_refused():
    r = Replay(ListSource(recording(10)), GroundStationState)
    assert r.control({"action": "seek", "t": "soon"})[0] is False
    assert r.control({"action": "seek", "t": float("nan")})[0] is False
    assert r.control({"action": "speed", "speed": 1000})[0] is False
    assert r.control({"action": "rewind"})[0] is False


def test_pause_stops_time():
    r = Replay(ListSource(recording(50)), GroundStationState)
    r.control({"action": "play"})
    r.step(1.0)
    r.control({"action": "pause"})
    r.step(5.0)
    assert r.frame()["replay"]["t"] == pytest.approx(11.0)
