"""Graph layout with Graphviz ``dot`` (Debian's graphviz package): DOT text -> SVG text."""
from __future__ import annotations

import hashlib
import subprocess
import threading
from collections import OrderedDict

__all__ = ["LayoutError", "SvgRenderer"]


class LayoutError(RuntimeError):
    """dot failed or is missing."""


MAX_DOT_PROCESSES = 2  # dot runs at once; more requests wait (up to the timeout), then fail


class SvgRenderer:
    """Runs ``dot -Tsvg`` with a timeout and caches results by DOT text (layouts are reused while only
    the status changes, which is what the page highlights). At most ``max_processes`` dot processes run
    at once, whatever the number of clients."""

    def __init__(self, dot_path: str = "dot", timeout_s: float = 10.0, cache_size: int = 32,
                 max_processes: int = MAX_DOT_PROCESSES) -> None:
        self._dot = dot_path
        self._timeout = timeout_s
        self._cache: OrderedDict[str, str] = OrderedDict()
        self._cache_size = cache_size
        self._lock = threading.Lock()
        self._max_processes = max_processes
        self._slots = threading.BoundedSemaphore(max_processes)

    def render(self, dot_text: str) -> str:
        key = hashlib.sha1(dot_text.encode("utf-8")).hexdigest()
        with self._lock:
            if key in self._cache:
                self._cache.move_to_end(key)
                return self._cache[key]
        if not self._slots.acquire(timeout=self._timeout):
            raise LayoutError("layout busy: %d dot processes already running" % self._max_processes)
        try:
            with self._lock:  # another request may have laid out the same graph while we waited
                if key in self._cache:
                    return self._cache[key]
            proc = subprocess.run([self._dot, "-Tsvg"], input=dot_text.encode("utf-8"), capture_output=True,
                                  timeout=self._timeout, check=False)
        except (OSError, subprocess.TimeoutExpired) as ex:
            raise LayoutError("could not run %s: %s" % (self._dot, ex)) from None
        finally:
            self._slots.release()
        if proc.returncode != 0:
            raise LayoutError("dot failed: %s" % proc.stderr.decode("utf-8", "replace")[:500])
        svg = proc.stdout.decode("utf-8", "replace")
        start = svg.find("<svg")
        svg = svg[start:] if start >= 0 else svg
        with self._lock:
            self._cache[key] = svg
            while len(self._cache) > self._cache_size:
                self._cache.popitem(last=False)
        return svg
