"""The viewer's HTTP server: the page, JSON snapshots, SVG layouts, server-sent events, init and debugger
commands.

Standard library only (http.server), bound to localhost by default; the page has no external resources.
Rules that keep other web sites and slow clients out:

* the ``Host`` header must name this server (one of ``allowed_hosts``, with or without the port): a page of
  another site whose name was re-pointed at 127.0.0.1 (DNS rebinding) gets 403;
* a POST must carry ``Content-Type: application/json`` (a cross-site HTML form cannot) and, when the
  browser says where it comes from (``Origin``, ``Sec-Fetch-Site``), come from this server's own page;
* every socket read or write times out after ``SOCKET_TIMEOUT_S``; at most ``MAX_CLIENTS`` connections are
  served at once (more get 503) and at most ``MAX_EVENT_STREAMS`` of them may be event streams.
"""
from __future__ import annotations

import json
import os
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Callable, Iterable, Optional
from urllib.parse import parse_qs, urlparse

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
LOCAL_HOSTS = ("localhost", "127.0.0.1", "::1")

# set_initial_state(server, path, state) -> error text or "" on success
InitFn = Callable[[str, str, str], str]
# send_debug(server, command) -> error text or "" on success
DebugFn = Callable[[str, dict], str]


def _no_debugger(server: str, command: dict) -> str:
    return "this viewer has no debugger connection"


def host_name(header: str) -> str:
    """The host part of a Host header or of an Origin's netloc ('[::1]:8087' -> '::1')."""
    header = header.strip().lower()
    if header.startswith("["):
        return header[1:header.find("]")] if "]" in header else header
    return header.rsplit(":", 1)[0] if header.count(":") == 1 else header


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
        self.allowed_hosts = {h.lower().strip("[]") for h in (*LOCAL_HOSTS, host, *allowed_hosts)}
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

        class Handler(BaseHTTPRequestHandler):
            server_version = "smach_web_viewer/1"
            protocol_version = "HTTP/1.1"
            timeout = viewer.socket_timeout_s  # every read and write on the socket

            def log_message(self, fmt: str, *args: object) -> None:  # quiet
                pass

            def _send(self, code: int, body: bytes, ctype: str) -> None:
                self.send_response(code)
                self.send_header("Content-Type", ctype)
                self.send_header("Content-Length", str(len(body)))
                self.send_header("Cache-Control", "no-store")
                self.send_header("X-Content-Type-Options", "nosniff")
                self.end_headers()
                self.wfile.write(body)

            def _json(self, code: int, obj: object) -> None:
                self._send(code, json.dumps(obj).encode("utf-8"), "application/json")

            def _host_ok(self) -> bool:
                host = self.headers.get("Host", "")
                if host_name(host) in viewer.allowed_hosts:
                    return True
                self._json(403, {"error": "Host %r is not this viewer (allowed: %s; see ~allowed_hosts)"
                                 % (host[:100], sorted(viewer.allowed_hosts))})
                return False

            def _same_origin_json(self) -> bool:
                """A POST must be JSON and, if the browser names its origin, come from our own page."""
                ctype = self.headers.get("Content-Type", "").split(";", 1)[0].strip().lower()
                if ctype != "application/json":
                    self._json(415, {"error": "POST bodies must be application/json"})
                    return False
                origin = self.headers.get("Origin")
                if origin is not None:
                    parsed = urlparse(origin)
                    if origin == "null" or parsed.netloc.lower() != self.headers.get("Host", "").lower():
                        self._json(403, {"error": "cross-origin request refused (Origin %r)" % origin[:100]})
                        return False
                if self.headers.get("Sec-Fetch-Site", "same-origin") not in ("same-origin", "none"):
                    self._json(403, {"error": "cross-site request refused"})
                    return False
                return True

            def _read_json(self) -> Optional[dict]:
                try:
                    length = int(self.headers.get("Content-Length", "0"))
                except ValueError:
                    length = -1
                if length < 0 or length > MAX_BODY:
                    self._json(400, {"error": "bad Content-Length"})
                    return None
                try:
                    req = json.loads(self.rfile.read(length) or b"{}")
                except ValueError as ex:
                    self._json(400, {"error": "body is not JSON: %s" % ex})
                    return None
                if not isinstance(req, dict):
                    self._json(400, {"error": "body must be a JSON object"})
                    return None
                return req

            def do_GET(self) -> None:  # noqa: N802
                if not self._host_ok():
                    return
                url = urlparse(self.path)
                if url.path in ("/", "/index.html"):
                    self._send(200, viewer._page, "text/html; charset=utf-8")
                elif url.path == "/api/state":
                    self._json(200, viewer.model.snapshot())
                elif url.path == "/api/graph":
                    query = parse_qs(url.query)
                    server = query.get("server", [""])[0]
                    collapsed = [p for p in query.get("collapsed", [""])[0].split(",") if p]
                    dot = viewer.model.dot(server, collapsed)
                    if dot is None:
                        self._json(404, {"error": "unknown server %r" % server})
                        return
                    try:
                        svg = viewer.renderer.render(dot)
                    except LayoutError as ex:
                        self._json(500, {"error": str(ex)})
                        return
                    self._send(200, svg.encode("utf-8"), "image/svg+xml")
                elif url.path == "/api/events":
                    self._events()
                else:
                    self._json(404, {"error": "not found"})

            def do_POST(self) -> None:  # noqa: N802
                if not self._host_ok() or not self._same_origin_json():
                    self.close_connection = True
                    return
                url = urlparse(self.path)
                if url.path not in ("/api/set_initial_state", "/api/debug"):
                    self._json(404, {"error": "not found"})
                    return
                req = self._read_json()
                if req is None:
                    return
                if url.path == "/api/debug":
                    server, command = str(req.get("server", "")), {k: v for k, v in req.items() if k != "server"}
                    error = viewer.send_debug(server, command)
                else:
                    try:
                        server, path, state = str(req["server"]), str(req["path"]), str(req["state"])
                    except KeyError as ex:
                        self._json(400, {"error": "expected JSON {server, path, state}: missing %s" % ex})
                        return
                    error = viewer.set_initial_state(server, path, state)
                if error:
                    self._json(400, {"error": error})
                else:
                    self._json(200, {"ok": True})

            def _events(self) -> None:
                if not viewer._streams.acquire(blocking=False):
                    self._json(503, {"error": "too many event streams"})
                    return
                try:
                    self._stream_events()
                finally:
                    viewer._streams.release()

            def _stream_events(self) -> None:
                self.send_response(200)
                self.send_header("Content-Type", "text/event-stream")
                self.send_header("Cache-Control", "no-store")
                self.send_header("Connection", "close")
                self.end_headers()
                self.close_connection = True
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
