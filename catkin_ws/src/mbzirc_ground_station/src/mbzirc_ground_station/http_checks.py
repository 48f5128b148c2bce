"""Who may talk to the ground station: Host and Origin checks, request bodies (pure, no sockets).

The station binds to 127.0.0.1 by default. A browser page of another site could still send requests to it
(cross-site requests, DNS rebinding), so every request must name an allowed Host, a request with an Origin
must come from an allowed origin, and commands must be JSON (`Content-Type: application/json`, which a
cross-site form cannot send without a preflight the station never grants).
"""
from __future__ import annotations

import json
from typing import Iterable, Optional
from urllib.parse import urlsplit

__all__ = ["allowed_hosts", "check_host_origin", "parse_json_body", "MAX_BODY"]

MAX_BODY = 16 * 1024
LOCAL_NAMES = ("127.0.0.1", "localhost", "[::1]")


def allowed_hosts(bind_host: str, port: int, extra: Iterable[str] = ()) -> frozenset[str]:
    """Host header values accepted: the local names and the bound address with the port, plus `extra`
    (each 'name' or 'name:port'; a bare name gets the port)."""
    names = set(LOCAL_NAMES)
    if bind_host not in ("", "0.0.0.0", "::"):
        names.add("[%s]" % bind_host if ":" in bind_host else bind_host)
    out = {"%s:%d" % (n, port) for n in names}
    for e in extra:
        e = str(e).strip().lower()
        if e:
            out.add(e if e.rsplit(":", 1)[-1].isdigit() and not e.endswith("]") else "%s:%d" % (e, port))
    if port == 80:
        out |= set(names)
    return frozenset(h.lower() for h in out)


def check_host_origin(host: Optional[str], origin: Optional[str], allowed: frozenset[str]) -> Optional[str]:
    """None when the request may be served, else the reason to refuse it (HTTP 403)."""
    if not host or host.strip().lower() not in allowed:
        return "Host %r not allowed" % (host,)
    if origin is None:
        return None            # not from a browser page (curl, rostopic-like scripts): Host decides
    if origin == "null":
        return "Origin 'null' not allowed"
    parts = urlsplit(origin)
    if parts.scheme != "http" or not parts.netloc or parts.netloc.lower() not in allowed:
        return "Origin %r not allowed" % origin
    return None


def parse_json_body(content_type: Optional[str], length_header: Optional[str], read) -> tuple[Optional[dict], str]:
    """(object, '') from a JSON POST body, or (None, reason). `read(n)` reads n bytes of the body."""
    if (content_type or "").split(";")[0].strip().lower() != "application/json":
        return None, "Content-Type must be application/json"
    try:
        length = int(length_header or "")
    except ValueError:
        return None, "Content-Length required"
    if length < 0 or length > MAX_BODY:
        return None, "body too large"
    try:
        obj = json.loads(read(length) or b"null")
    except (ValueError, UnicodeDecodeError) as ex:
        return None, "body is not JSON: %s" % ex
    if not isinstance(obj, dict):
        return None, "body must be a JSON object"
    return obj, ""
