"""Service calls that give up after a bounded wall time instead of hanging with a lost link.

Why: rospy's ServiceProxy looks the service up at the master and talks to the server with no timeout of
its own (the socket's is 60 s or more). An agent cut from the ground station (Wi-Fi drop) would hang in
its first call to the region manager or, in simulation, to the simulator's UAL: the heartbeat watchdog's
safe stop (pump off, hold, home) would never run. A bounded call fails fast with ServiceTimeout, and a
call still hanging on one service makes the next calls to it fail at once rather than pile up threads.
"""
from __future__ import annotations

import threading
from typing import Any, Callable


class ServiceTimeout(RuntimeError):
    """The service did not answer within the bound (or an earlier call to it still hangs)."""


class BoundedCall:
    """Wraps a callable proxy: call(*args) returns its answer, or raises ServiceTimeout after `timeout` s."""

    def __init__(self, name: str, proxy: Callable[..., Any], timeout: float) -> None:
        self.name = name
        self.proxy = proxy
        self.timeout = float(timeout)
        self._pending: threading.Thread | None = None
        self._lock = threading.Lock()

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        with self._lock:
            if self._pending is not None and self._pending.is_alive():
                raise ServiceTimeout(f'service {self.name}: an earlier call has not returned yet')
            box: dict = {}

            def work() -> None:
                try:
                    box['value'] = self.proxy(*args, **kwargs)
                except Exception as e:  # noqa: BLE001 - re-raised in the caller's thread
                    box['error'] = e
            worker = threading.Thread(target=work, name=f'call {self.name}', daemon=True)
            self._pending = worker
            worker.start()
        worker.join(self.timeout)
        if worker.is_alive():
            raise ServiceTimeout(f'service {self.name} did not answer in {self.timeout:.1f} s')
        if 'error' in box:
            raise box['error']
        return box['value']

    def __getattr__(self, key: str) -> Any:
        """The proxy's other attributes (e.g. wait_for_service) pass through."""
        return getattr(self.proxy, key)
