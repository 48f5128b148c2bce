"""HTTP checks (Host, Origin, content type) as the station sets them, and the server's routes, commands and
event stream."""
import http.client
import json

import pytest

from mbzirc_ground_station.commands import parse_command
from mbzirc_ground_station.live import LiveSource
from mbzirc_ground_station.state import GroundStationState
from mbzirc_ground_station.web import GroundStationServer

from mbzirc_ros_utils.local_http import SameSitePolicy
from msgs import feed

POLICY = SameSitePolicy("127.0.0.1", 8088)


@pytest.mark.parametrize("host,origin,ok", [
    ("127.0.0.1:8088", None, True), ("localhost:8088", "http://localhost:8088", True),
    ("[::1]:8088", "http://127.0.0.1:8088", True),
    ("evil.example:8088", None, False),             # DNS rebinding: a foreign name for our address
    ("127.0.0.1:8088", "http://evil.example", False), ("127.0.0.1:8088", "null", False),
    ("127.0.0.1:8088", "https://127.0.0.1:8088", False), (None, None, False), ("127.0.0.1:9999", None, False)])
def test_host_and_origin(host, origin, ok):
    assert (POLICY.check(host, origin) is None) == ok


def test_allowed_extra_names_and_bound_address():
    p = SameSitePolicy("0.0.0.0", 8088, ["gcs-laptop", "10.0.0.5:8088"])
    assert all(p.host_ok(h) for h in ("gcs-laptop:8088", "10.0.0.5:8088", "127.0.0.1:8088", "[::1]:8088"))
    assert not any(p.host_ok(h) for h in ("0.0.0.0:8088", "gcs-laptop:9", "10.0.0.5", "gcs-laptop"))
    assert SameSitePolicy("10.0.0.7", 80).host_ok("10.0.0.7")      # no port in the Host: port 80


def test_commands_checked():
    assert parse_command({"command": "send_home", "robot": "2"}, ["1", "2"])[0].robot == "2"
    assert parse_command({"command": "send_home", "robot": 2}, ["1", "2"])[0].robot == "2"
    assert parse_command({"command": "send_home", "robot": "all"}, ["1"])[0].robot == "all"
    assert parse_command({"command": "send_home", "robot": "7"}, ["1"])[0] is None
    assert parse_command({"command": "send_home"}, ["1"])[0] is None
    assert parse_command({"command": "self_destruct"}, ["1"])[0] is None
    assert parse_command({"command": "land_all"}, [])[0].name == "land_all"


@pytest.fixture
def station():
    calls = []
    state = GroundStationState()
    live = LiveSource(state, lambda: 5.0, run_command=lambda c: (calls.append(c), (True, "ok"))[1])
    live.apply("/mbzirc2020_2/data_feed", feed("2", 1.0, 2.0, 3.0))
    web = GroundStationServer(live, {"mode": "live", "arena": None}, live.command, "127.0.0.1", 0)
    web.start()
    yield web, calls
    web.stop()


def request(web, method, path, body=None, headers=None):
    c = http.client.HTTPConnection("127.0.0.1", web.port, timeout=10)
    h = {"Host": "127.0.0.1:%d" % web.port}
    h.update(headers or {})
    c.request(method, path, body=body, headers=h)
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, r.getheader("Content-Type"), data


def test_page_and_state(station):
    web, _ = station
    code, ctype, body = request(web, "GET", "/")
    assert code == 200 and ctype.startswith("text/html") and b"EventSource" in body
    code, ctype, body = request(web, "GET", "/api/state")
    assert code == 200 and ctype == "application/json"
    frame = json.loads(body)
    assert frame["robots"][0]["pose"]["x"] == 1.0 and "tracks" in frame


def test_foreign_host_and_origin_refused(station):
    web, calls = station
    assert request(web, "GET", "/", headers={"Host": "evil.example:%d" % web.port})[0] == 403
    body = json.dumps({"command": "land_all"})
    code, _, _ = request(web, "POST", "/api/command", body, {"Origin": "http://evil.example",
                                                               "Content-Type": "application/json"})
    assert code == 403 and calls == []


def test_links_from_other_pages_open_but_their_posts_are_refused(station):
    """A link from the SMACH viewer's port (same site) opens the page; a POST from there is refused."""
    web, calls = station
    assert request(web, "GET", "/", headers={"Sec-Fetch-Site": "same-site"})[0] == 200
    assert request(web, "GET", "/", headers={"Sec-Fetch-Site": "cross-site"})[0] == 200
    body = json.dumps({"command": "land_all"})
    for site in ("same-site", "cross-site"):
        assert request(web, "POST", "/api/command", body, {"Content-Type": "application/json",
                                                             "Sec-Fetch-Site": site})[0] == 403
    assert calls == []


def test_command_needs_json_content_type(station):
    web, calls = station
    body = json.dumps({"command": "land_all"})
    assert request(web, "POST", "/api/command", body, {"Content-Type": "text/plain"})[0] == 415
    assert calls == []


def test_command_runs_and_is_logged(station):
    web, calls = station
    origin = "http://127.0.0.1:%d" % web.port
    code, _, body = request(web, "POST", "/api/command", json.dumps({"command": "send_home", "robot": "2"}),
                            {"Content-Type": "application/json", "Origin": origin})
    assert code == 200 and json.loads(body)["ok"] is True and calls[0].name == "send_home"
    code, _, body = request(web, "POST", "/api/command", json.dumps({"command": "send_home", "robot": "9"}),
                            {"Content-Type": "application/json"})
    assert code == 400 and len(calls) == 1
    log = [e["text"] for e in json.loads(request(web, "GET", "/api/state")[2])["log"]]
    assert log == ["send_home UAV 2: sent", "send_home UAV 2: done - ok", "refused: robot must be 'all' or one "
                   "of ['2'], not '9'"]


def test_replay_controls_refused_live(station):
    web, _ = station
    assert request(web, "POST", "/api/replay", json.dumps({"action": "play"}),
                   {"Content-Type": "application/json"})[0] == 409


def test_event_stream_starts_with_info_and_a_full_frame(station):
    web, _ = station
    c = http.client.HTTPConnection("127.0.0.1", web.port, timeout=10)
    c.request("GET", "/api/events", headers={"Host": "127.0.0.1:%d" % web.port})
    r = c.getresponse()
    assert r.status == 200 and r.getheader("Content-Type") == "text/event-stream"
    lines = []
    while sum(1 for x in lines if x.startswith(b"data: ")) < 2:
        lines.append(r.fp.readline())
    events = [x for x in lines if x.startswith(b"event: ")]
    data = [json.loads(x[6:]) for x in lines if x.startswith(b"data: ")]
    assert events == [b"event: info\n", b"event: frame\n"]
    assert data[0]["mode"] == "live" and "tracks" in data[1]
    c.close()


def test_release_calls_each_robots_release_service():
    """Release (one robot or all): the agents' operator/release service, one call per robot."""
    from mbzirc_ground_station.commands import Command
    from mbzirc_ground_station.ros_adapter import CommandRunner
    state = GroundStationState()
    live = LiveSource(state, lambda: 5.0)
    for rid in ("1", "2"):
        live.apply("/mbzirc2020_%s/data_feed" % rid, feed(rid, 1.0, 2.0, 3.0))
    runner = CommandRunner(live)
    called = []
    runner._call = lambda name, srv_type, *args: (called.append((name, srv_type.__name__)), (True, name))[1]
    assert runner(Command("release", "2")) == (True, "/mbzirc2020_2/operator/release")
    assert runner(Command("release", "all"))[0]
    assert called == [("/mbzirc2020_2/operator/release", "Trigger"), ("/mbzirc2020_1/operator/release", "Trigger"),
                      ("/mbzirc2020_2/operator/release", "Trigger")]
    assert parse_command({"command": "release"}, ["1"])[0] is None     # a robot (or "all") is needed
