"""The ground station's HTTP server: the page, JSON snapshots, server-sent events, commands, replay controls.

Standard library only (http.server). One frame clock builds a frame from the cached state `rate` times a
second and serialises it once; every open page's event stream sends the newest frame (a slow page skips
frames, it never queues them), so the ROS graph is never asked anything per frame and memory stays bounded
whatever the number of pages. The page reconnects by itself (EventSource) when the server restarts.
"""
from __future__ import annotations

import json
import os
import socket
import threading
import time
from http.server import ThreadingHTTPServer
from typing import Callable, Optional, Protocol
from urllib.parse import urlparse

from mbzirc_ros_utils.local_http import JsonRequestHandler, SameSitePolicy

__all__ = ["FrameSource", "GroundStationServer", "PAGE_PATH"]

PAGE_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "static", "index.html")
SSE_KEEPALIVE_S = 5.0
FULL_FRAME_EVERY = 10     # tracks (the heavy part) go in every 10th frame and in a page's first frame
SSE_RETRY_MS = 1000
SOCKET_TIMEOUT_S = 20.0
SSE_SEND_BUFFER = 32 * 1024   # bytes; about 3 frames


class _Server(ThreadingHTTPServer):
    request_queue_size = 64   # many pages reconnect at once after a restart


class FrameSource(Protocol):
    """Where frames come from: the live state or a replay."""

    def frame(self, tracks: bool = False) -> dict: ...


class GroundStationServer:
    """Serves one FrameSource.

    Routes: ``GET /`` page; ``GET /api/state`` a full frame; ``GET /api/info`` arena, mode, links;
    ``GET /api/events`` server-sent events (``info`` first, then ``frame``); ``POST /api/command``
    (operator command, JSON); ``POST /api/replay`` (replay controls, JSON; replay mode only).

    Args:
        source: frames to serve; if it has ``step(wall_dt)`` (a Replay) the frame clock calls it.
        info: static data for the page (arena, mode, smach viewer URL, commands).
        command: ``command(request) -> (http code, reply)``; None = commands disabled (replay).
        host, port: where to listen (port 0 = any free port); allowed_extra: more allowed Host names.
        rate: frames per second; max_clients: open event streams at most (others get 503).
    """

    def __init__(self, source: FrameSource, info: dict, command: Optional[Callable[[dict], tuple[int, dict]]] = None,
                 host: str = "127.0.0.1", port: int = 8088, allowed_extra: tuple = (), rate: float = 10.0,
                 max_clients: int = 50) -> None:
        self.source = source
        self.info = info
        self.command = command
        self.period = 1.0 / max(1.0, rate)
        self.max_clients = max_clients
        self.clients = 0
        self._stop = threading.Event()
        self._cond = threading.Condition()
        self._seq = 0
        self._frame_bytes = b""
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
        with self._cond:
            self._cond.notify_all()
        self.httpd.shutdown()
        self.httpd.server_close()

    # ------------------------------------------------------------------ frames
    def _build(self, full: bool) -> bytes:
        frame = self.source.frame(tracks=full)
        frame["seq"] = self._seq
        frame["wall"] = round(time.time(), 3)
        return json.dumps(frame, separators=(",", ":")).encode("utf-8")

    def _frame_clock(self) -> None:
        last = time.monotonic()
        while not self._stop.is_set():
            now = time.monotonic()
            step = getattr(self.source, "step", None)
            if step is not None:
                step(now - last)
            last = now
            if self.clients == 0:      # nobody watching: no frames (the state still follows the messages)
                self._stop.wait(self.period)
                continue
            full = self._seq % FULL_FRAME_EVERY == 0
            try:
                data = self._build(full)
            except Exception as ex:  # noqa: BLE001 - a bad frame must not stop the clock
                data = json.dumps({"error": "frame failed: %s" % ex, "seq": self._seq}).encode("utf-8")
            with self._cond:
                self._frame_bytes = data
                self._seq += 1
                self._cond.notify_all()
            self._stop.wait(max(0.0, self.period - (time.monotonic() - now)))

    def latest(self, after: int, timeout: float) -> tuple[int, bytes]:
        """The newest frame once its sequence number is > after (or after timeout: (after, b''))."""
        with self._cond:
            self._cond.wait_for(lambda: self._seq > after or self._stop.is_set(), timeout)
            if self._seq > after:
                return self._seq, self._frame_bytes
            return after, b""

    # ------------------------------------------------------------------ HTTP
    def _make_handler(self) -> type:
        server = self

        class Handler(JsonRequestHandler):
            server_version = "mbzirc_ground_station/1"
            timeout = SOCKET_TIMEOUT_S   # a page that stops reading is dropped, its thread freed

            @property
            def policy(self) -> SameSitePolicy:   # made once the port is bound
                return server.policy

            def do_GET(self) -> None:  # noqa: N802
                if self.refused():
                    return
                path = urlparse(self.path).path
                if path in ("/", "/index.html"):
                    self.send_body(200, server._page, "text/html; charset=utf-8")
                elif path == "/api/state":
                    self.send_body(200, server._build(True), "application/json")
                elif path == "/api/info":
                    self.send_json(200, server.info)
                elif path == "/api/events":
                    self._events()
                else:
                    self.send_json(404, {"error": "not found"})

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
                control = getattr(server.source, "control", None)
                if control is None:
                    self.send_json(409, {"error": "not a replay"})
                    return
                ok, why = control(req)
                self.send_json(200 if ok else 400, {"ok": ok, "error": why} if not ok else {"ok": True})

            def _events(self) -> None:
                with server._cond:
                    if server.clients >= server.max_clients:
                        busy = True
                    else:
                        busy = False
                        server.clients += 1
                if busy:
                    self.send_json(503, {"error": "too many pages open"})
                    return
                try:
                    # a small send buffer: a page that reads slowly gets fresh frames late, not a queue of old ones
                    self.connection.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SSE_SEND_BUFFER)
                    self.start_event_stream()
                    self.wfile.write(("retry: %d\nevent: info\ndata: %s\n\n"
                                      % (SSE_RETRY_MS, json.dumps(server.info))).encode("utf-8"))
                    seq = server._seq
                    self.wfile.write(b"event: frame\ndata: " + server._build(True) + b"\n\n")
                    self.wfile.flush()
                    while not server._stop.is_set():
                        new, data = server.latest(seq, SSE_KEEPALIVE_S)
                        if new == seq:
                            self.wfile.write(b": keepalive\n\n")
                        else:
                            seq = new
                            self.wfile.write(b"event: frame\ndata: " + data + b"\n\n")
                        self.wfile.flush()
                except (BrokenPipeError, ConnectionResetError, OSError):
                    pass
                finally:
                    with server._cond:
                        server.clients -= 1

        return Handler
