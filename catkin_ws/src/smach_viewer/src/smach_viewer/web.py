"""The viewer's HTTP server: the page, JSON snapshots, SVG layouts, server-sent events, init commands.

Standard library only (http.server), bound to localhost by default; the page has no external resources.
"""
from __future__ import annotations

import json
import os
import threading
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Callable, Optional
from urllib.parse import parse_qs, urlparse

from smach_viewer.layout import LayoutError, SvgRenderer
from smach_viewer.model import ViewerModel

__all__ = ["ViewerHttpServer", "PAGE_PATH"]

PAGE_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "static", "index.html")
MAX_BODY = 64 * 1024
SSE_KEEPALIVE_S = 10.0
SSE_MIN_PERIOD_S = 0.05  # at most 20 pushes per second per client

# set_initial_state(server, path, state) -> error text or "" on success
InitFn = Callable[[str, str, str], str]


class ViewerHttpServer:
    """Serves the page and API for a :class:`ViewerModel`.

    Routes: ``GET /`` page; ``GET /api/state`` snapshot JSON; ``GET /api/graph?server=S`` SVG;
    ``GET /api/events`` server-sent events (a ``state`` event with the snapshot on every change);
    ``POST /api/set_initial_state`` JSON ``{server, path, state}``.
    """

    def __init__(self, model: ViewerModel, set_initial_state: InitFn, host: str = "127.0.0.1", port: int = 8087,
                 renderer: Optional[SvgRenderer] = None) -> None:
        self.model = model
        self.set_initial_state = set_initial_state
        self.renderer = renderer or SvgRenderer()
        self._stop = threading.Event()
        with open(PAGE_PATH, "rb") as f:
            self._page = f.read()
        handler = self._make_handler()
        self.httpd = ThreadingHTTPServer((host, port), handler)
        self.httpd.daemon_threads = True
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

            def do_GET(self) -> None:  # noqa: N802
                url = urlparse(self.path)
                if url.path in ("/", "/index.html"):
                    self._send(200, viewer._page, "text/html; charset=utf-8")
                elif url.path == "/api/state":
                    self._json(200, viewer.model.snapshot())
                elif url.path == "/api/graph":
                    server = parse_qs(url.query).get("server", [""])[0]
                    dot = viewer.model.dot(server)
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
                url = urlparse(self.path)
                if url.path != "/api/set_initial_state":
                    self._json(404, {"error": "not found"})
                    return
                try:
                    length = int(self.headers.get("Content-Length", "0"))
                except ValueError:
                    length = -1
                if length < 0 or length > MAX_BODY:
                    self._json(400, {"error": "bad Content-Length"})
                    return
                try:
                    req = json.loads(self.rfile.read(length) or b"{}")
                    server, path, state = str(req["server"]), str(req["path"]), str(req["state"])
                except (ValueError, KeyError, TypeError) as ex:
                    self._json(400, {"error": "expected JSON {server, path, state}: %s" % ex})
                    return
                error = viewer.set_initial_state(server, path, state)
                if error:
                    self._json(400, {"error": error})
                else:
                    self._json(200, {"ok": True})

            def _events(self) -> None:
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
