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


# ---- hardening: Host / Origin / Content-Type, slow sockets, client and dot caps -----------------------
def raw_request(port, text, timeout=5):
    import socket
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as s:
        s.sendall(text.encode())
        data = b""
        while True:
            try:
                chunk = s.recv(65536)
            except socket.timeout:
                break
            if not chunk:
                break
            data += chunk
        return data


def test_foreign_host_header_is_refused(viewer):
    _, web, _, _ = viewer
    reply = raw_request(web.port, "GET /api/state HTTP/1.1\r\nHost: evil.example:%d\r\nConnection: close\r\n\r\n"
                        % web.port)
    assert reply.startswith(b"HTTP/1.1 403") and b"evil.example" in reply
    for host in ("localhost:%d" % web.port, "127.0.0.1", "[::1]:%d" % web.port):
        reply = raw_request(web.port, "GET /api/state HTTP/1.1\r\nHost: %s\r\nConnection: close\r\n\r\n" % host)
        assert reply.startswith(b"HTTP/1.1 200"), host


def test_posts_must_be_same_origin_json(viewer):
    _, web, calls, base = viewer
    body = b'{"server": "/srv", "path": "/ROOT", "state": "B"}'

    def post_with(headers):
        req = urllib.request.Request(base + "/api/set_initial_state", data=body, method="POST", headers=headers)
        try:
            with urllib.request.urlopen(req, timeout=5) as r:
                return r.status
        except urllib.error.HTTPError as ex:
            return ex.code

    assert post_with({"Content-Type": "text/plain"}) == 415                      # what a cross-site form sends
    assert post_with({"Content-Type": "application/x-www-form-urlencoded"}) == 415
    assert post_with({"Content-Type": "application/json", "Origin": "http://evil.example"}) == 403
    assert post_with({"Content-Type": "application/json", "Origin": "null"}) == 403
    assert post_with({"Content-Type": "application/json", "Sec-Fetch-Site": "cross-site"}) == 403
    assert calls == []
    assert post_with({"Content-Type": "application/json; charset=utf-8", "Origin": base}) == 200
    assert calls == [("/srv", "/ROOT", "B")]


def test_slow_socket_times_out_and_clients_are_capped():
    import socket
    import time
    model = ViewerModel()
    web = ViewerHttpServer(model, lambda *a: "", "127.0.0.1", 0, max_clients=2, socket_timeout_s=1.0)
    web.start()
    try:
        slow = [socket.create_connection(("127.0.0.1", web.port)) for _ in range(2)]
        for s in slow:
            s.sendall(b"GET / HTTP/1.1\r\n")  # never finishes its request
        # both slots taken: a third client gets 503 at once
        reply = raw_request(web.port, "GET /api/state HTTP/1.1\r\nHost: localhost\r\n\r\n", timeout=2)
        assert reply.startswith(b"HTTP/1.1 503")
        # the slow ones are cut after the socket timeout, which frees the slots
        for s in slow:
            s.settimeout(3)
            assert s.recv(100) == b""  # closed by the server, no answer to a request never finished
            s.close()
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            reply = raw_request(web.port, "GET /api/state HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n\r\n")
            if reply.startswith(b"HTTP/1.1 200"):
                break
        assert reply.startswith(b"HTTP/1.1 200")
    finally:
        web.stop()


def test_dot_processes_are_capped(tmp_path):
    import threading as th
    fake = tmp_path / "slow_dot"
    fake.write_text("#!/bin/sh\ncat > /dev/null\necho $$ >> %s/pids\nsleep 0.5\necho '<svg></svg>'\n" % tmp_path)
    fake.chmod(0o755)
    r = SvgRenderer(str(fake), timeout_s=5, max_processes=1)
    running, peak, lock = [0], [0], th.Lock()
    errors = []

    def one(i):
        try:
            r.render("digraph { n%d }" % i)
        except LayoutError as ex:
            errors.append(ex)

    threads = [th.Thread(target=one, args=(i,)) for i in range(3)]
    import subprocess as sp
    real_run = sp.run

    def counting_run(*a, **k):
        with lock:
            running[0] += 1
            peak[0] = max(peak[0], running[0])
        try:
            return real_run(*a, **k)
        finally:
            with lock:
                running[0] -= 1

    sp.run = counting_run
    try:
        for t in threads:
            t.start()
        for t in threads:
            t.join(10)
    finally:
        sp.run = real_run
    assert peak[0] == 1 and not errors
    busy = SvgRenderer(str(fake), timeout_s=0.1, max_processes=1)
    busy._slots.acquire()
    with pytest.raises(LayoutError, match="busy"):
        busy.render("digraph { z }")


def test_debug_api_forwards_commands():
    model = ViewerModel()
    sent = []
    web = ViewerHttpServer(model, lambda *a: "", "127.0.0.1", 0,
                           send_debug=lambda server, cmd: sent.append((server, cmd)) or "")
    web.start()
    try:
        base = "http://127.0.0.1:%d" % web.port
        assert post(base + "/api/debug", b'{"server": "/s", "cmd": "break", "path": "/R/A", "on": true}') == \
            (200, {"ok": True})
        assert sent == [("/s", {"cmd": "break", "path": "/R/A", "on": True})]
        assert post(base + "/api/debug", b"[1]")[0] == 400
    finally:
        web.stop()


def test_collapsed_container_graph():
    model = ViewerModel()
    model.update_structure("/t", "/R", ["A", "B"], [], [], [], ["done"])
    assert "rankdir=TB" in model.dot("/t")  # small containers: top-down
    model.update_structure("/s", "/R", ["A", "SUB"], ["go", "x"], ["A", "SUB"], ["SUB", "done"], ["done"])
    model.update_structure("/s", "/R/SUB", ["X"], ["x"], ["X"], ["None"], ["x"])
    dot = model.dot("/s", ["/R/SUB"])
    assert '"/R/SUB" [id="s:/R/SUB"' in dot and "/R/SUB/X" not in dot and "cluster_/R/SUB" not in dot
    assert '"/R/A" -> "/R/SUB"' in dot and '"/R/SUB" -> "/R:done"' in dot
    assert "cluster_/R/SUB" in model.dot("/s")


def hundred_state_model():
    """10 nested machines of 10 states each, chained, under one root: a 100-state machine."""
    model = ViewerModel()
    subs = ["SUB%d" % i for i in range(10)]
    model.update_structure("/s", "/R", subs, ["done"] * 9 + ["done"], subs, subs[1:] + ["end"], ["end"])
    for sub in subs:
        states = ["%s_S%d" % (sub, j) for j in range(10)]
        model.update_structure("/s", "/R/" + sub, states, ["next"] * 10, states, states[1:] + ["done"], ["done"])
    return model, subs


def test_hundred_states_collapse_to_a_small_graph():
    model, subs = hundred_state_model()
    full = model.dot("/s")
    folded = model.dot("/s", ["/R/" + s for s in subs])
    assert full.count("shape=ellipse") == 100
    assert "rankdir=LR" in full  # containers of 10 states: left-right
    assert folded.count("shape=ellipse") == 0 and folded.count("shape=box3d") == 10
    if shutil.which("dot"):
        import time
        r = SvgRenderer()
        start = time.monotonic()
        svg = r.render(full)
        full_s = time.monotonic() - start
        start = time.monotonic()
        r.render(folded)
        folded_s = time.monotonic() - start
        assert svg.count('class="node"') >= 100
        print("dot layout of a 100-state machine: %.2f s, all 10 containers collapsed: %.2f s" % (full_s, folded_s))
