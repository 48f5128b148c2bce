"""AgentInterface: the one owner of an agent's publishers, subscribers, services and clients.

Why (the thesis's design): a task only coordinates components (UAL, actuators, detectors, estimator,
region manager) through the interface, which routes each message or request to the task that is active
now. ROS is reached through a *backend* object (`ros_backend.RosBackend`; a fake one in the unit tests).
"""
from __future__ import annotations

import threading
from typing import Any, Callable, Dict, List, Optional


class AgentInterface:
    """Owns the node's publishers, subscribers, service servers and clients.

    A subscriber or service is created once per name; tasks register callbacks on it. A message goes to
    the callbacks of the tasks active now (a task and the sub-tasks it is running) and to the always-on
    callbacks (task None). A service request goes to the callback of the innermost active task that
    registered one, else to the service's default (inactive) callback.
    """

    def __init__(self, backend: Any) -> None:
        self.backend = backend
        self._subs: Dict[str, dict] = {}
        self._services: Dict[str, dict] = {}
        self._pubs: Dict[str, Any] = {}
        self._clients: Dict[str, Any] = {}
        self._active: List[str] = []          # stack: top-level task, then its running sub-tasks
        self._demands: Dict[str, list] = {}   # task name -> [(topic, type)] subscribed only while it runs
        self._demand_subs: Dict[str, list] = {}
        self._lock = threading.Lock()
        self._open = threading.Event()        # messages are dispatched only while open (see close)
        self._open.set()

    # -- activity
    def push_active(self, task_name: str) -> None:
        """A task (or sub-task) starts: its callbacks receive data from now on, its demands open."""
        with self._lock:
            self._active.append(task_name)
            demands = list(self._demands.get(task_name, []))
        subs = []
        for topic, msg_type, callback in demands:
            try:
                subs.append((topic, self.backend.subscriber(topic, msg_type, self._guarded(topic, callback))))
            except Exception as e:  # noqa: BLE001 - a producer switched off costs time, not the task
                self.backend.logerr(f'{task_name}: could not subscribe to {topic}: {e!r}')
        if subs:
            with self._lock:
                self._demand_subs.setdefault(task_name, []).extend(subs)

    def pop_active(self, task_name: str) -> None:
        """A task ends: its callbacks stop receiving, its demands close.

        The demands are closed in a thread of their own: unregistering a subscriber tells the ROS master,
        with no time bound, and a robot whose link is cut cannot reach it. Done in the state machine's
        thread, that call held the task's end for good, so a permanently cut UAV never went home (fault
        suite, a cut during extinguish_facade_fire)."""
        with self._lock:
            if task_name in self._active:
                self._active.remove(task_name)
            subs = self._demand_subs.pop(task_name, [])
        unregisters = [u for u in (getattr(sub, 'unregister', None) for _topic, sub in subs) if u is not None]
        if unregisters:
            self.backend.start_thread(f'{task_name}: closing demands', lambda: [u() for u in unregisters])

    def add_demand(self, task_name: str, topic: str, msg_type: Any,
                   callback: Optional[Callable[[Any], None]] = None) -> None:
        """Subscribe to topic only while task_name runs; its messages go to callback (None: dropped).

        Why: a lazy node (circle_detector ~lazy) works only while one of its outputs has a subscriber, and
        the always-on `sensed_objects` cannot say so (the estimator listens to it all the time): there the
        subscription's existence is the request. And a heavy topic only one task reads (the raw thermal
        image, 14 frames a sim-second per robot) costs its deserialisation in every frame of the trial when
        subscribed for good (`add_subscriber`), though the task runs a small part of it.
        """
        with self._lock:
            self._demands.setdefault(task_name, []).append((topic, msg_type, callback))

    def _guarded(self, topic: str, callback: Optional[Callable[[Any], None]]) -> Callable[[Any], None]:
        """callback, its exceptions logged (throttled) instead of raised in the subscriber's thread."""
        if callback is None:
            return lambda _msg: None

        return lambda msg: self._call(topic, callback, msg)

    def _call(self, topic: str, callback: Callable[[Any], None], msg: Any) -> None:
        try:
            callback(msg)
        except Exception as e:   # a bad message must not kill the subscriber thread
            self.backend.logerr_throttle(5.0, f'callback for {topic} failed: {e!r}')

    def demanded_topics(self) -> List[str]:
        """Topics subscribed now because a running task demands them."""
        with self._lock:
            return [topic for subs in self._demand_subs.values() for topic, _ in subs]

    def active_tasks(self) -> List[str]:
        """Names of the active tasks, outermost first."""
        with self._lock:
            return list(self._active)

    # -- topics
    def add_subscriber(self, task_name: Optional[str], topic: str, msg_type: Any,
                       callback: Callable[[Any], None]) -> None:
        """Route messages of topic to callback while task_name is active (always when None)."""
        with self._lock:
            entry = self._subs.get(topic)
            if entry is None:
                entry = {'type': msg_type, 'callbacks': {}}
                self._subs[topic] = entry
                create = True
            else:
                if entry['type'] is not msg_type:
                    raise TypeError(f'topic {topic} already subscribed with another type')
                create = False
            entry['callbacks'].setdefault(task_name, []).append(callback)
        if create:
            self.backend.subscriber(topic, msg_type, lambda msg, t=topic: self._dispatch(t, msg))

    def close(self) -> None:
        """Drop incoming messages until open(). Why: rospy delivers from the moment a subscriber exists, so
        a callback may run before the agent that registered it is built (realistic + GNSS-denied seed 101:
        a UAV's first ual/pose failed on an attribute set later in the constructor; its home was never
        settled and every refill failed 'home unknown' for the rest of the trial)."""
        self._open.clear()

    def open(self) -> None:
        self._open.set()

    def _dispatch(self, topic: str, msg: Any) -> None:
        if not self._open.is_set():
            return
        with self._lock:
            entry = self._subs[topic]
            names = [None] + list(self._active)
            callbacks = [cb for n in names for cb in entry['callbacks'].get(n, [])]
        for cb in callbacks:
            self._call(topic, cb, msg)

    def add_publisher(self, topic: str, msg_type: Any, latch: bool = False) -> Any:
        """The (shared) publisher of topic."""
        with self._lock:
            if topic not in self._pubs:
                self._pubs[topic] = self.backend.publisher(topic, msg_type, latch)
            return self._pubs[topic]

    # -- services
    def add_service_server(self, task_name: Optional[str], name: str, srv_type: Any,
                           callback: Optional[Callable[[Any], Any]] = None,
                           default_callback: Optional[Callable[[Any], Any]] = None) -> None:
        """Serve name: requests go to task_name's callback while it is active, else to the default."""
        with self._lock:
            entry = self._services.get(name)
            create = entry is None
            if create:
                entry = {'type': srv_type, 'callbacks': {}, 'default': None}
                self._services[name] = entry
            if callback is not None:
                entry['callbacks'][task_name] = callback
            if default_callback is not None:
                entry['default'] = default_callback
        if create:
            self.backend.service(name, srv_type, lambda req, n=name: self._serve(n, req))

    def _serve(self, name: str, req: Any) -> Any:
        with self._lock:
            entry = self._services[name]
            cb = None
            for n in reversed(self._active):
                if n in entry['callbacks']:
                    cb = entry['callbacks'][n]
                    break
            if cb is None:
                cb = entry['callbacks'].get(None) or entry['default']
        if cb is None:
            raise RuntimeError(f'service {name}: no active task serves it and no default callback')
        return cb(req)

    def add_client(self, name: str, srv_type: Any) -> Any:
        """The (shared) client of service name."""
        with self._lock:
            if name not in self._clients:
                self._clients[name] = self.backend.service_proxy(name, srv_type)
            return self._clients[name]
