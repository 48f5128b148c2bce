"""Small web servers on the operator's computer, kept out of reach of other web sites (standard library only).

Used by the web ground station and the SMACH web viewer. Both bind to 127.0.0.1 by default, but a page of
any other site open in the same browser can still send requests to them:

* DNS rebinding: a foreign name re-pointed at 127.0.0.1 makes the browser treat our server as that site.
  Rule: every request must name this server in its ``Host`` header (`SameSitePolicy.check`).
* Cross-site requests (CSRF): a foreign page may POST to us. Rules: a request whose ``Origin`` shows
  another site, or a POST whose ``Sec-Fetch-Site`` is not same-origin, is refused, and a POST body must be ``application/json``, which an
  HTML form cannot send and a script of another origin cannot send without a CORS preflight that these
  servers never grant (`parse_json_body`).

`JsonRequestHandler` holds the replies both servers send (headers that stop content sniffing, framing and
caching; JSON errors; the start of an event stream).
"""
from __future__ import annotations

import json
from http.server import BaseHTTPRequestHandler
from typing import Any, Callable, Iterable, Optional
from urllib.parse import urlsplit

__all__ = ["SameSitePolicy", "split_host", "parse_json_body", "JsonRequestHandler", "LOCAL_NAMES", "MAX_BODY"]

LOCAL_NAMES = ("127.0.0.1", "localhost", "::1")
MAX_BODY = 16 * 1024          # bytes of a JSON request body at most
ANY_ADDRESS = ("", "0.0.0.0", "::")


def split_host(value: str) -> tuple[str, Optional[int]]:
    """A Host header or an Origin's netloc as (name, port): '[::1]:8087' -> ('::1', 8087), 'Gcs' -> ('gcs',
    None). A port that is not a number gives port -1 (matches nothing)."""
    value = value.strip().lower()
    if value.startswith("["):
        end = value.find("]")
        if end < 0:
            return value, -1
        name, rest = value[1:end], value[end + 1:]
    elif value.count(":") == 1:
        name, rest = value.split(":")
        rest = ":" + rest
    else:
        name, rest = value, ""
    if not rest:
        return name, None
    port = rest[1:]
    return name, int(port) if rest.startswith(":") and port.isdigit() else -1


class SameSitePolicy:
    """Which requests come from this server's own pages (see the module's rules).

    Args:
        bind_host: the address the server listens on (named in Host headers too, unless it is any address).
        port: the port the Host must name (a Host without a port means 80); None = any port, the name decides.
        extra: more names the server may be opened with ('gcs-laptop' on the server's port, or 'name:port').
    """

    def __init__(self, bind_host: str, port: Optional[int], extra: Iterable[str] = ()) -> None:
        self.port = port
        self.names = set(LOCAL_NAMES)
        if bind_host not in ANY_ADDRESS:
            self.names.add(bind_host.strip("[]").lower())
        self.exact: set[tuple[str, Optional[int]]] = set()
        for e in extra:
            name, p = split_host(str(e))
            if not name:
                continue
            if p is None:
                self.names.add(name)
            else:
                self.exact.add((name, p))

    def host_ok(self, value: str) -> bool:
        name, port = split_host(value)
        if (name, port) in self.exact:
            return True
        if name not in self.names:
            return False
        return self.port is None or port == self.port or (port is None and self.port == 80)

    def check(self, host: Optional[str], origin: Optional[str] = None,
              fetch_site: Optional[str] = None) -> Optional[str]:
        """None when the request may be served, else why it is refused (answer 403)."""
        if not host or not self.host_ok(host):
            return "Host %r not allowed (allowed names: %s, see ~allowed_hosts)" % (
                (host or "")[:100], ", ".join(sorted(self.names | {n for n, _ in self.exact})))
        if origin is not None:           # sent by browsers on POSTs and cross-origin requests
            parts = urlsplit(origin)
            if origin == "null" or parts.scheme != "http" or not parts.netloc or not self.host_ok(parts.netloc):
                return "cross-origin request refused (Origin %r)" % origin[:100]
        if fetch_site not in (None, "same-origin", "none"):
            return "cross-site request refused (Sec-Fetch-Site %r)" % fetch_site[:40]
        return None


def parse_json_body(content_type: Optional[str], length_header: Optional[str], read: Callable[[int], bytes],
                    max_body: int = MAX_BODY) -> tuple[Optional[dict], str]:
    """(object, '') from a JSON POST body, or (None, reason). `read(n)` reads n bytes of the body."""
    if (content_type or "").split(";")[0].strip().lower() != "application/json":
        return None, "Content-Type must be application/json"
    try:
        length = int(length_header or "")
    except ValueError:
        return None, "Content-Length required"
    if length < 0 or length > max_body:
        return None, "body too large (at most %d bytes)" % max_body
    try:
        obj = json.loads(read(length) or b"null")
    except (ValueError, UnicodeDecodeError) as ex:
        return None, "body is not JSON: %s" % ex
    if not isinstance(obj, dict):
        return None, "body must be a JSON object"
    return obj, ""


class JsonRequestHandler(BaseHTTPRequestHandler):
    """A quiet HTTP/1.1 handler with the replies of a JSON API; subclasses set `policy` and `max_body`."""

    protocol_version = "HTTP/1.1"
    policy: SameSitePolicy
    max_body = MAX_BODY

    def log_message(self, fmt: str, *args: Any) -> None:  # the servers log what matters themselves
        pass

    def send_body(self, code: int, body: bytes, ctype: str) -> None:
        self.send_response(code)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.send_header("X-Frame-Options", "DENY")
        self.end_headers()
        self.wfile.write(body)

    def send_json(self, code: int, obj: object) -> None:
        self.send_body(code, json.dumps(obj).encode("utf-8"), "application/json")

    def refused(self) -> bool:
        """True (after answering 403) when the request is not from this server's own pages. Sec-Fetch-Site
        is judged on POSTs only: a GET may be a link followed from another page (the SMACH viewer's port is
        'same-site'), and it changes nothing."""
        h = self.headers
        why = self.policy.check(h.get("Host"), h.get("Origin"),
                                h.get("Sec-Fetch-Site") if self.command == "POST" else None)
        if why:
            self.close_connection = True
            self.send_json(403, {"error": why})
        return bool(why)

    def read_json(self) -> Optional[dict]:
        """The request's JSON object, or None after answering 415 / 400 with the reason."""
        req, why = parse_json_body(self.headers.get("Content-Type"), self.headers.get("Content-Length"),
                                   self.rfile.read, self.max_body)
        if req is None:
            self.close_connection = True   # the unread body must not be taken for the next request
            self.send_json(415 if "Content-Type" in why else 400, {"error": why})
        return req

    def start_event_stream(self) -> None:
        """Headers of a server-sent event stream (the connection closes when the stream ends)."""
        self.send_response(200)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.send_header("Connection", "close")
        self.end_headers()
        self.close_connection = True
