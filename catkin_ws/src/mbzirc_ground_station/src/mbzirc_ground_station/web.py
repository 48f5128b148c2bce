"""The ground station's HTTP server: the page, JSON snapshots, server-sent events, commands, replay controls,
and the recorded trials a page may pick for replay.

Standard library only (http.server). Each channel (the main one: the live trial or the replay the server
was started with; one more per recording a page picked) has one frame: a single frame clock builds it from
the cached state `rate` times a second and serialises it once; every page watching that channel gets the
newest frame over its event stream (a slow page skips frames, it never queues them), so the ROS graph is
never asked anything per frame and memory stays bounded whatever the number of pages. The page reconnects
by itself (EventSource) when the server restarts.
"""
from __future__ import annotations

import json
import os
import socket
import threading
import time
from http.server import ThreadingHTTPServer
from typing import Any, Callable, Optional, Protocol
from urllib.parse import parse_qs, urlparse

from mbzirc_ros_utils.local_http import JsonRequestHandler, SameSitePolicy

from .floor_maps import FloorMaps
from .recordings import RecordingError, Recordings

__all__ = ["FrameSource", "GroundStationServer", "PAGE_PATH"]

PAGE_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "static", "index.html")
SSE_KEEPALIVE_S = 5.0
FULL_FRAME_EVERY = 10     # tracks (the heavy part) go in every 10th frame and in a page's first frame
SSE_RETRY_MS = 1000
SOCKET_TIMEOUT_S = 20.0
SSE_SEND_BUFFER = 32 * 1024   # bytes; about 3 frames
MAX_PICKED_REPLAYS = 3        # recordings open at once for pages that picked them
PICKED_IDLE_S = 60.0          # wall s a picked recording stays open with no page watching it

# open(path, name) -> (a replay, the page's info for it): how a picked recording is opened
OpenReplay = Callable[[str, str], tuple[Any, dict]]


class _Server(ThreadingHTTPServer):
    request_queue_size = 64   # many pages reconnect at once after a restart


class FrameSource(Protocol):
    """Where frames come from: the live state or a replay."""

    def frame(self, tracks: bool = False) -> dict: ...


class _Channel:
    """One stream of frames: a source (None: no trial, only the picker), its page info, its newest frame."""

    def __init__(self, source: Optional[FrameSource], info: dict) -> None:
        self.source = source
        self.info = info
        self.cond = threading.Condition()
        self.seq = 0
        self.frame_bytes = b""
        self.clients = 0
        self.idle_since = time.monotonic()

    def build(self, full: bool) -> bytes:
        frame = self.source.frame(tracks=full)
        frame["seq"] = self.seq
        frame["wall"] = round(time.time(), 3)
        return json.dumps(frame, separators=(",", ":")).encode("utf-8")

    def latest(self, after: int, timeout: float, stop: threading.Event) -> tuple[int, bytes]:
        """The newest frame once its sequence number is > after (or after timeout: (after, b''))."""
        with self.cond:
            self.cond.wait_for(lambda: self.seq > after or stop.is_set(), timeout)
            if self.seq > after:
                return self.seq, self.frame_bytes
            return after, b""


class GroundStationServer:
    """Serves one FrameSource, and the recordings under a results directory when one is given.

    Routes (``?bag=<name>``: the recording a page picked, else the main channel): ``GET /`` page;
    ``GET /api/state`` a full frame; ``GET /api/info`` arena, mode, links; ``GET /api/events`` server-sent
    events (``info`` first, then ``frame``); ``GET /api/recordings`` the recordings to pick from;
    ``POST /api/command`` (operator command, JSON; main channel, live only); ``POST /api/replay`` (replay
    controls, JSON, ``"bag"`` names a picked recording).

    Args:
        source: frames to serve; if it has ``step(wall_dt)`` (a Replay) the frame clock calls it; None: no
            trial of its own (the replay tool started without a bag: only the picker).
        info: static data for the page (arena, mode, smach viewer URL, commands).
        command: ``command(request) -> (http code, reply)``; None = commands disabled (replay).
        host, port: where to listen (port 0 = any free port); allowed_extra: more allowed Host names.
        rate: frames per second; max_clients: open event streams at most (others get 503).
        recordings, open_replay: the recordings pages may pick and how one is opened; None = no picker.
    """

    def __init__(self, source: Optional[FrameSource], info: dict,
                 command: Optional[Callable[[dict], tuple[int, dict]]] = None, host: str = "127.0.0.1",
                 port: int = 8088, allowed_extra: tuple = (), rate: float = 10.0, max_clients: int = 50,
                 recordings: Optional[Recordings] = None, open_replay: Optional[OpenReplay] = None,
                 maps: Optional[FloorMaps] = None) -> None:
        self.maps = maps   # the SLAM floor maps (live only), fetched by the page apart from the frames
        self.main = _Channel(source, dict(info, recordings=recordings is not None and open_replay is not None))
        self.command = command
        self.recordings = recordings if open_replay is not None else None
        self.open_replay = open_replay
        self.picked: dict[str, _Channel] = {}
        self._picked_lock = threading.Lock()
        self.period = 1.0 / max(1.0, rate)
        self.max_clients = max_clients
        self.clients = 0
        self._clients_lock = threading.Lock()
        self._stop = threading.Event()
        with open(PAGE_PATH, "rb") as f:
            self._page = f.read()
        self.httpd = _Server((host, port), self._make_handler())
        self.httpd.daemon_threads = True
        self.policy = SameSitePolicy(host, self.port, allowed_extra)
        self._threads: list[threading.Thread] = []

    @property
    def port(self) -> int:
        return self.httpd.server_address[1]

    def start(self) -> None:
        for target, name in ((self.httpd.serve_forever, "gcs_http"), (self._frame_clock, "gcs_frames")):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)

    def stop(self) -> None:
        self._stop.set()
        for ch in self._channels():
            with ch.cond:
                ch.cond.notify_all()
        self.httpd.shutdown()
        self.httpd.server_close()
        with self._picked_lock:
            for ch in self.picked.values():
                ch.source.close()
            self.picked.clear()

    # ------------------------------------------------------------------ channels
    def _channels(self) -> list[_Channel]:
        with self._picked_lock:
            return [self.main, *self.picked.values()]

    def channel(self, bag: str) -> _Channel:
        """The main channel ('') or the picked recording `bag`, opened on first use; RecordingError else."""
        if not bag:
            return self.main
        if self.recordings is None:
            raise RecordingError("this ground station offers no recordings", 404)
        with self._picked_lock:
            ch = self.picked.get(bag)
            if ch is not None:
                ch.idle_since = time.monotonic()    # asked for: not closed as idle in the next minute
                return ch
            path = self.recordings.resolve(bag)
            if len(self.picked) >= MAX_PICKED_REPLAYS:
                self._close_idle(5.0)
                if len(self.picked) >= MAX_PICKED_REPLAYS:
                    raise RecordingError("%d recordings are open in other pages: close one first"
                                         % MAX_PICKED_REPLAYS, 503)
            try:
                source, info = self.open_replay(path, bag)
            except Exception as ex:  # noqa: BLE001 - a damaged bag is the page's error, not the server's
                raise RecordingError("cannot read %r: %s" % (bag, ex)) from None
            ch = self.picked[bag] = _Channel(source, dict(info, recordings=True))
            return ch

    def _close_idle(self, idle_s: float) -> None:
        """Close picked recordings no page watched for idle_s (the caller holds _picked_lock)."""
        now = time.monotonic()
        with self._clients_lock:
            idle = [name for name, ch in self.picked.items() if ch.clients == 0 and now - ch.idle_since >= idle_s]
        for name in idle:
            self.picked.pop(name).source.close()

    # ------------------------------------------------------------------ frames
    def _frame_clock(self) -> None:
        last = time.monotonic()
        while not self._stop.is_set():
            now = time.monotonic()
            for ch in self._channels():
                self._tick(ch, now - last)
            with self._picked_lock:
                self._close_idle(PICKED_IDLE_S)
            last = now
            self._stop.wait(max(0.0, self.period - (time.monotonic() - now)))

    def _tick(self, ch: _Channel, wall_dt: float) -> None:
        if ch.source is None:
            return
        step = getattr(ch.source, "step", None)
        if step is not None:
            step(wall_dt)
        if ch.clients == 0:      # nobody watching: no frames (the state still follows the messages)
            return
        try:
            data = ch.build(ch.seq % FULL_FRAME_EVERY == 0)
        except Exception as ex:  # noqa: BLE001 - a bad frame must not stop the clock
            data = json.dumps({"error": "frame failed: %s" % ex, "seq": ch.seq}).encode("utf-8")
        with ch.cond:
            ch.frame_bytes = data
            ch.seq += 1
            ch.cond.notify_all()

    # ------------------------------------------------------------------ HTTP
    def _recordings_list(self) -> dict:
        return {"dir": self.recordings.root, "bags": [r._asdict() for r in self.recordings.list()]}

    def _make_handler(self) -> type:
        server = self

        class Handler(JsonRequestHandler):
            server_version = "mbzirc_ground_station/1"
            timeout = SOCKET_TIMEOUT_S   # a page that stops reading is dropped, its thread freed

            @property
            def policy(self) -> SameSitePolicy:   # made once the port is bound
                return server.policy

            def _channel(self, bag: object) -> Optional[_Channel]:
                """The channel the request names, or None after answering why not."""
                try:
                    return server.channel(bag if isinstance(bag, str) else "")
                except RecordingError as ex:
                    self.send_json(ex.code, {"error": str(ex), "bag": str(bag)[:200]})
                    return None

            def do_GET(self) -> None:  # noqa: N802
                if self.refused():
                    return
                url = urlparse(self.path)
                bag = parse_qs(url.query).get("bag", [""])[0]
                if url.path in ("/", "/index.html"):
                    self.send_body(200, server._page, "text/html; charset=utf-8")
                elif url.path == "/api/recordings":
                    if server.recordings is None:
                        self.send_json(404, {"error": "this ground station offers no recordings"})
                    else:
                        self.send_json(200, server._recordings_list())
                elif url.path == "/api/maps":
                    self._maps(parse_qs(url.query).get("since", [""])[0], bag)
                elif url.path in ("/api/state", "/api/info", "/api/events"):
                    ch = self._channel(bag)
                    if ch is None:
                        return
                    if url.path == "/api/info":
                        self.send_json(200, ch.info)
                    elif url.path == "/api/events":
                        self._events(ch)
                    elif ch.source is None:
                        self.send_json(404, {"error": "no trial here: pick a recording"})
                    else:
                        self.send_body(200, ch.build(True), "application/json")
                else:
                    self.send_json(404, {"error": "not found"})

            def _maps(self, since: str, bag: str) -> None:
                """The maps, or only their version when the page has it (?since=<version>); none in replay."""
                if server.maps is None or bag:
                    self.send_json(200, {"version": 0, "maps": []})
                    return
                self.send_json(200, server.maps.snapshot(int(since) if since.isdigit() else None))

            def do_POST(self) -> None:  # noqa: N802
                if self.refused():
                    return
                path = urlparse(self.path).path
                if path not in ("/api/command", "/api/replay"):
                    self.send_json(404, {"error": "not found"})
                    return
                req = self.read_json()
                if req is None:
                    return
                if path == "/api/command":
                    if server.command is None:
                        self.send_json(409, {"error": "no commands in replay"})
                        return
                    code, reply = server.command(req)
                    self.send_json(code, reply)
                    return
                ch = self._channel(req.get("bag", ""))
                if ch is None:
                    return
                control = getattr(ch.source, "control", None)
                if control is None:
                    self.send_json(409, {"error": "not a replay"})
                    return
                ok, why = control(req)
                self.send_json(200 if ok else 400, {"ok": ok, "error": why} if not ok else {"ok": True})

            def _events(self, ch: _Channel) -> None:
                with server._clients_lock:
                    busy = server.clients >= server.max_clients
                    if not busy:
                        server.clients += 1
                        ch.clients += 1
                if busy:
                    self.send_json(503, {"error": "too many pages open"})
                    return
                try:
                    # a small send buffer: a page that reads slowly gets fresh frames late, not a queue of old ones
                    self.connection.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SSE_SEND_BUFFER)
                    self.start_event_stream()
                    self.wfile.write(("retry: %d\nevent: info\ndata: %s\n\n"
                                      % (SSE_RETRY_MS, json.dumps(ch.info))).encode("utf-8"))
                    seq = ch.seq
                    if ch.source is not None:
                        self.wfile.write(b"event: frame\ndata: " + ch.build(True) + b"\n\n")
                    self.wfile.flush()
                    while not server._stop.is_set():
                        new, data = ch.latest(seq, SSE_KEEPALIVE_S, server._stop)
                        if new == seq:
                            self.wfile.write(b": keepalive\n\n")
                        else:
                            seq = new
                            self.wfile.write(b"event: frame\ndata: " + data + b"\n\n")
                        self.wfile.flush()
                except (BrokenPipeError, ConnectionResetError, OSError):
                    pass
                finally:
                    with server._clients_lock:
                        server.clients -= 1
                        ch.clients -= 1
                        ch.idle_since = time.monotonic()

        return Handler
