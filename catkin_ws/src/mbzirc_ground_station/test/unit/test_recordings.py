"""The recordings a page may pick: listed under the results directory; traversal, links out and non-bags
refused with the reason; a picked one is replayed on its own channel beside the server's own trial."""
import http.client
import json
import os
import shutil
from urllib.parse import quote

import pytest

from mbzirc_ground_station.bag_source import open_bag_replay
from mbzirc_ground_station.live import LiveSource
from mbzirc_ground_station.recordings import BAG_MAGIC, RecordingError, Recordings, default_results_dir
from mbzirc_ground_station.state import GroundStationState
from mbzirc_ground_station.web import GroundStationServer

from msgs import feed

BAG = os.path.join(os.path.dirname(__file__), "..", "data", "short_mission.bag")


@pytest.fixture
def results(tmp_path):
    """results/trial_a/mission.bag (a real bag), notes.txt, fake.bag (not a rosbag), a link to a bag outside,
    and a bag outside the directory."""
    root = tmp_path / "results"
    (root / "trial_a").mkdir(parents=True)
    shutil.copy(BAG, root / "trial_a" / "mission.bag")
    (root / "notes.txt").write_text("not a bag")
    (root / "fake.bag").write_bytes(b"hello, not a rosbag")
    outside = tmp_path / "secret.bag"
    outside.write_bytes(BAG_MAGIC + b"x")
    os.symlink(outside, root / "link.bag")
    return root


def test_list_only_bags_under_the_directory(results):
    names = [r.name for r in Recordings(str(results)).list()]
    assert sorted(names) == ["fake.bag", "link.bag", "trial_a/mission.bag"]
    assert Recordings(str(results / "none_yet")).list() == []


@pytest.mark.parametrize("name,code,why", [
    ("../secret.bag", 400, "'..' is refused"), ("trial_a/../../secret.bag", 400, "'..' is refused"),
    ("/etc/passwd", 400, "absolute paths are refused"), ("notes.txt", 400, "is not a bag"),
    ("fake.bag", 400, "is not a rosbag"), ("link.bag", 400, "outside the results directory"),
    ("trial_b/mission.bag", 404, "no recording"), ("", 400, "name a recording"), (7, 400, "name a recording")])
def test_bad_names_refused_with_the_reason(results, name, code, why):
    with pytest.raises(RecordingError, match=why) as ex:
        Recordings(str(results)).resolve(name)
    assert ex.value.code == code


def test_good_name_resolves_inside(results):
    path = Recordings(str(results)).resolve("trial_a/mission.bag")
    assert path == os.path.realpath(results / "trial_a" / "mission.bag")


def test_default_results_dir_is_the_repositorys():
    # catkin_ws/src/mbzirc_ground_station -> <repository>/results, where make mission writes
    here = os.path.dirname(os.path.abspath(__file__))
    assert default_results_dir() == os.path.normpath(os.path.join(here, "..", "..", "..", "..", "..", "results"))


@pytest.fixture
def station(results):
    live = LiveSource(GroundStationState(), lambda: 5.0, run_command=lambda c: (True, "ok"))
    live.apply("/mbzirc2020_2/data_feed", feed("2", 1.0, 2.0, 3.0))
    web = GroundStationServer(live, {"mode": "live", "arena": None}, live.command, "127.0.0.1", 0,
                              recordings=Recordings(str(results)),
                              open_replay=lambda path, name: open_bag_replay(path, None, name))
    web.start()
    yield web
    web.stop()


def request(web, method, path, body=None):
    c = http.client.HTTPConnection("127.0.0.1", web.port, timeout=10)
    h = {"Host": "127.0.0.1:%d" % web.port}
    if body is not None:
        h["Content-Type"] = "application/json"
        body = json.dumps(body)
    c.request(method, path, body=body, headers=h)
    r = c.getresponse()
    data = json.loads(r.read())
    c.close()
    return r.status, data


def test_recordings_listed_and_a_picked_one_replayed(station):
    web = station
    code, info = request(web, "GET", "/api/info")
    assert code == 200 and info["mode"] == "live" and info["recordings"] is True
    code, listed = request(web, "GET", "/api/recordings")
    assert code == 200 and "trial_a/mission.bag" in [b["name"] for b in listed["bags"]]
    q = "?bag=" + quote("trial_a/mission.bag")
    code, info = request(web, "GET", "/api/info" + q)
    assert code == 200 and info["mode"] == "replay" and info["bag"] == "trial_a/mission.bag"
    code, frame = request(web, "GET", "/api/state" + q)
    start = frame["replay"]["start"]
    assert code == 200 and frame["replay"]["t"] < start
    assert request(web, "POST", "/api/replay", {"bag": "trial_a/mission.bag", "action": "seek", "t": start + 20})[0] \
        == 200
    code, frame = request(web, "GET", "/api/state" + q)
    assert frame["replay"]["t"] == start + 20 and [r["id"] for r in frame["robots"]] == ["0", "1", "2", "3"]
    code, live = request(web, "GET", "/api/state")       # the live trial is untouched
    assert "replay" not in live and [r["id"] for r in live["robots"]] == ["2"]
    assert request(web, "POST", "/api/replay", {"action": "play"})[0] == 409   # the live channel is no replay


@pytest.mark.parametrize("name,code", [("../secret.bag", 400), ("notes.txt", 400), ("fake.bag", 400),
                                       ("link.bag", 400), ("nope.bag", 404)])
def test_picked_names_refused_on_every_route(station, name, code):
    q = "?bag=" + quote(name)
    for path in ("/api/info", "/api/state", "/api/events"):
        got, reply = request(station, "GET", path + q)
        assert got == code and reply["error"], path
    got, reply = request(station, "POST", "/api/replay", {"bag": name, "action": "play"})
    assert got == code and reply["error"]
    assert station.picked == {}


def test_no_recordings_without_a_directory():
    live = LiveSource(GroundStationState(), lambda: 5.0)
    web = GroundStationServer(live, {"mode": "live", "arena": None}, None, "127.0.0.1", 0)
    web.start()
    try:
        assert request(web, "GET", "/api/info")[1]["recordings"] is False
        assert request(web, "GET", "/api/recordings")[0] == 404
        assert request(web, "GET", "/api/state?bag=x.bag")[0] == 404
    finally:
        web.stop()


def test_picked_recordings_bounded_and_closed_when_idle(station, results):
    for i in range(4):
        shutil.copy(BAG, results / ("t%d.bag" % i))
    for i in range(3):
        assert request(station, "GET", "/api/info?bag=t%d.bag" % i)[0] == 200
    code, reply = request(station, "GET", "/api/info?bag=t3.bag")
    assert code == 503 and "close one first" in reply["error"]
    first = station.picked["t0.bag"]
    closed = []
    first.source.close = lambda: closed.append("t0.bag")
    first.idle_since -= 3600.0                      # nobody watched it for an hour
    assert request(station, "GET", "/api/info?bag=t3.bag")[0] == 200
    assert closed == ["t0.bag"] and sorted(station.picked) == ["t1.bag", "t2.bag", "t3.bag"]
