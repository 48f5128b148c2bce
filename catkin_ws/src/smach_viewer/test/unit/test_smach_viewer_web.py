"""The HTTP server without ROS: page, snapshot, SVG via dot, SSE, init commands and bad requests."""
import json
import re
import shutil
import threading
import urllib.error
import urllib.request

import pytest

from smach_ros.userdata_codec import encode_local_data
from smach_viewer.layout import LayoutError, SvgRenderer
from smach_viewer.model import ViewerModel
from smach_viewer.web import ViewerHttpServer


@pytest.fixture()
def viewer():
    model = ViewerModel()
    model.update_structure("/srv", "/ROOT", ["A", "B"], ["go"], ["A"], ["B"], ["done"])
    model.update_status("/srv", "/ROOT", ["A"], ["A"], encode_local_data({"k": 1}), "START")
    calls = []

    def set_init(server, path, state):
        calls.append((server, path, state))
        return "" if state in ("A", "B") else "no such state"

    web = ViewerHttpServer(model, set_init, "127.0.0.1", 0)
    web.start()
    yield model, web, calls, "http://127.0.0.1:%d" % web.port
    web.stop()


def get(url):
    with urllib.request.urlopen(url, timeout=5) as r:
        return r.status, r.headers.get("Content-Type"), r.read()


def post(url, body):
    req = urllib.request.Request(url, data=body, method="POST", headers={"Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as ex:
        return ex.code, json.loads(ex.read())


def test_page_is_self_contained(viewer):
    _, _, _, base = viewer
    status, ctype, body = get(base + "/")
    assert status == 200 and ctype.startswith("text/html")
    text = body.decode()
    assert not re.search(r'(src|href)\s*=\s*"(https?:)?//', text)
    assert "EventSource" in text


def test_state_and_graph(viewer):
    _, _, _, base = viewer
    snap = json.loads(get(base + "/api/state")[2])
    assert snap["servers"]["/srv"]["containers"]["/ROOT"]["userdata"] == {"k": 1}
    status, ctype, svg = get(base + "/api/graph?server=/srv")
    assert status == 200 and ctype == "image/svg+xml"
    assert b'id="s:/ROOT/A"' in svg and svg.startswith(b"<svg")
    with pytest.raises(urllib.error.HTTPError) as ex:
        get(base + "/api/graph?server=/nope")
    assert ex.value.code == 404


def test_events_stream_pushes_changes(viewer):
    model, _, _, base = viewer
    resp = urllib.request.urlopen(base + "/api/events", timeout=5)
    first = b""
    while not first.endswith(b"\n\n"):
        first += resp.read1(65536)
    assert first.startswith(b"event: state")
    model.update_status("/srv", "/ROOT", ["A"], ["B"], "", "TRANSITION")
    second = b""
    while b'"active_states": ["B"]' not in second:
        chunk = resp.read1(65536)
        assert chunk
        second += chunk
    resp.close()


def test_set_initial_state_api(viewer):
    _, _, calls, base = viewer
    assert post(base + "/api/set_initial_state", b'{"server": "/srv", "path": "/ROOT", "state": "B"}') == (200, {"ok": True})
    assert calls == [("/srv", "/ROOT", "B")]
    code, body = post(base + "/api/set_initial_state", b'{"server": "/srv", "path": "/ROOT", "state": "Z"}')
    assert code == 400 and "no such state" in body["error"]
    code, body = post(base + "/api/set_initial_state", b"not json")
    assert code == 400
    code, body = post(base + "/api/set_initial_state", b'{"server": "/srv"}')
    assert code == 400


def test_layout_errors():
    with pytest.raises(LayoutError):
        SvgRenderer("/nonexistent/dot").render("digraph {}")
    if shutil.which("dot"):
        with pytest.raises(LayoutError):
            SvgRenderer().render("this is not dot")
        r = SvgRenderer()
        a = r.render("digraph { a -> b }")
        assert a is r.render("digraph { a -> b }")  # cached
