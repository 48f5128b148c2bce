"""The viewer's HTTP server: the page, JSON snapshots, SVG layouts, server-sent events, init and debugger
commands.

Standard library only (http.server), bound to localhost by default; the page has no external resources.
Rules that keep other web sites and slow clients out:

* the ``Host`` header must name this server (one of ``allowed_hosts``, on any port): a page of another site
  whose name was re-pointed at 127.0.0.1 (DNS rebinding) gets 403;
* a POST must carry ``Content-Type: application/json`` (a cross-site HTML form cannot) and, when the
  browser says where it comes from (``Origin``, ``Sec-Fetch-Site``), come from this server's own page
  (these two rules: ``mbzirc_ros_utils.local_http``, shared with the web ground station);
* every socket read or write times out after ``SOCKET_TIMEOUT_S``; at most ``MAX_CLIENTS`` connections are
  served at once (more get 503) and at most ``MAX_EVENT_STREAMS`` of them may be event streams.
"""
from __future__ import annotations

import json
import os
import threading
from http.server import ThreadingHTTPServer
from typing import Any, Callable, Iterable, Optional
from urllib.parse import parse_qs, urlparse

from mbzirc_ros_utils.local_http import JsonRequestHandler, SameSitePolicy
from smach_viewer.layout import LayoutError, SvgRenderer
from smach_viewer.model import ViewerModel

__all__ = ["ViewerHttpServer", "PAGE_PATH"]

PAGE_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "static", "index.html")
MAX_BODY = 64 * 1024
SSE_KEEPALIVE_S = 10.0
SSE_MIN_PERIOD_S = 0.05  # at most 20 pushes per second per client
SOCKET_TIMEOUT_S = 20.0  # longer than the keepalive period, so an idle event stream is not cut
MAX_CLIENTS = 32
MAX_EVENT_STREAMS = 16

# set_initial_state(server, path, state) -> error text or "" on success
InitFn = Callable[[str, str, str], str]
# send_debug(server, command) -> error text or "" on success
DebugFn = Callable[[str, dict], str]


def _no_debugger(server: str, command: dict) -> str:
    return "this viewer has no debugger connection"


class _CappedHttpServer(ThreadingHTTPServer):
    """A ThreadingHTTPServer that serves at most ``max_clients`` connections at once (503 beyond)."""

    daemon_threads = True

    def __init__(self, address: tuple, handler: type, max_clients: int) -> None:
        self._slots = threading.BoundedSemaphore(max_clients)
        super().__init__(address, handler)

    def process_request(self, request: Any, client_address: Any) -> None:
        if not self._slots.acquire(blocking=False):
            try:
                request.settimeout(2.0)
                request.sendall(b"HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\nConnection: close\r\n\r\n")
            except OSError:
                pass
            self.shutdown_request(request)
            return
        super().process_request(request, client_address)

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self._slots.release()


class ViewerHttpServer:
    """Serves the page and API for a :class:`ViewerModel`.

    Routes: ``GET /`` page; ``GET /api/state`` snapshot JSON; ``GET /api/graph?server=S[&collapsed=P,P]``
    SVG; ``GET /api/events`` server-sent events (a ``state`` event with the snapshot on every change);
    ``POST /api/set_initial_state`` JSON ``{server, path, state}``; ``POST /api/debug`` JSON
    ``{server, cmd, path?, outcome?, on?}`` (a smach_ros.debugger command).

    ``allowed_hosts``: names the Host header may carry, besides the bound host and localhost.
    """

    def __init__(self, model: ViewerModel, set_initial_state: InitFn, host: str = "127.0.0.1", port: int = 8087,
                 renderer: Optional[SvgRenderer] = None, send_debug: DebugFn = _no_debugger,
                 allowed_hosts: Iterable[str] = (), max_clients: int = MAX_CLIENTS,
                 max_event_streams: int = MAX_EVENT_STREAMS, socket_timeout_s: float = SOCKET_TIMEOUT_S) -> None:
        self.model = model
        self.set_initial_state = set_initial_state
        self.send_debug = send_debug
        self.renderer = renderer or SvgRenderer()
        self.policy = SameSitePolicy(host, None, allowed_hosts)   # the Host's name decides, on any port
        self.socket_timeout_s = socket_timeout_s
        self._streams = threading.BoundedSemaphore(max_event_streams)
        self._stop = threading.Event()
        with open(PAGE_PATH, "rb") as f:
            self._page = f.read()
        handler = self._make_handler()
        self.httpd = _CappedHttpServer((host, port), handler, max_clients)
        self._thread: Optional[threading.Thread] = None

    @property
    def port(self) -> int:
        return self.httpd.server_address[1]

    def start(self) -> None:
        self._thread = threading.Thread(target=self.httpd.serve_forever, name="web_viewer_http", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self.httpd.shutdown()
        self.httpd.server_close()

    def _make_handler(self) -> type:
        viewer = self

        class Handler(JsonRequestHandler):
            server_version = "smach_web_viewer/1"
            timeout = viewer.socket_timeout_s  # every read and write on the socket
            policy = viewer.policy
            max_body = MAX_BODY

            def do_GET(self) -> None:  # noqa: N802
                if self.refused():
                    return
                url = urlparse(self.path)
                if url.path in ("/", "/index.html"):
                    self.send_body(200, viewer._page, "text/html; charset=utf-8")
                elif url.path == "/api/state":
                    self.send_json(200, viewer.model.snapshot())
                elif url.path == "/api/graph":
                    query = parse_qs(url.query)
                    server = query.get("server", [""])[0]
                    collapsed = [p for p in query.get("collapsed", [""])[0].split(",") if p]
                    dot = viewer.model.dot(server, collapsed)
                    if dot is None:
                        self.send_json(404, {"error": "unknown server %r" % server})
                        return
                    try:
                        svg = viewer.renderer.render(dot)
                    except LayoutError as ex:
                        self.send_json(500, {"error": str(ex)})
                        return
                    self.send_body(200, svg.encode("utf-8"), "image/svg+xml")
                elif url.path == "/api/events":
                    self._events()
                else:
                    self.send_json(404, {"error": "not found"})

            def do_POST(self) -> None:  # noqa: N802
                if self.refused():
                    return
                url = urlparse(self.path)
                if url.path not in ("/api/set_initial_state", "/api/debug"):
                    self.send_json(404, {"error": "not found"})
                    return
                req = self.read_json()
                if req is None:
                    return
                if url.path == "/api/debug":
                    server, command = str(req.get("server", "")), {k: v for k, v in req.items() if k != "server"}
                    error = viewer.send_debug(server, command)
                else:
                    try:
                        server, path, state = str(req["server"]), str(req["path"]), str(req["state"])
                    except KeyError as ex:
                        self.send_json(400, {"error": "expected JSON {server, path, state}: missing %s" % ex})
                        return
                    error = viewer.set_initial_state(server, path, state)
                if error:
                    self.send_json(400, {"error": error})
                else:
                    self.send_json(200, {"ok": True})

            def _events(self) -> None:
                if not viewer._streams.acquire(blocking=False):
                    self.send_json(503, {"error": "too many event streams"})
                    return
                try:
                    self._stream_events()
                finally:
                    viewer._streams.release()

            def _stream_events(self) -> None:
                self.start_event_stream()
                version = -1
                try:
                    while not viewer._stop.is_set():
                        new = viewer.model.wait_for_change(version, SSE_KEEPALIVE_S)
                        if new == version:
                            self.wfile.write(b": keepalive\n\n")
                        else:
                            version = new
                            data = json.dumps(viewer.model.snapshot())
                            self.wfile.write(("event: state\ndata: %s\n\n" % data).encode("utf-8"))
                        self.wfile.flush()
                        viewer._stop.wait(SSE_MIN_PERIOD_S)
                except (BrokenPipeError, ConnectionResetError, OSError):
                    return

        return Handler
