"""A step debugger for a running smach tree, driven over ROS topics (used by the web viewer).

Off unless the server allows it (``~smach_allow_debug`` param or ``allow_debug`` argument, default False):
a debugger can hold a robot in a state and force outcomes, so it must be asked for. When off, the server
only publishes a latched ``{"allowed": false}`` so that viewers can say why there is nothing to debug.

How it hooks in: every state of the tree (containers included) gets an instance-level ``execute`` that first
asks the debugger whether to stop there. No smach code changes and no cost when debugging is off (nothing is
wrapped). A state paused on entry waits, without running, until a command releases it: ``continue`` (run it),
``step`` (run it and stop at the next state entered anywhere in the tree) or ``force`` (return the given
outcome without running it). A preempt of the paused state releases it too, so that it can service the
preempt. Concurrence children pause independently (several states can be paused at once).

Wire protocol (std_msgs/String holding JSON, next to the standard topics, which stay as upstream):

* ``<server>/smach/debug/command`` (subscribed): ``{"id": any, "cmd": C, ...}`` with C one of
  ``break`` (``path``, ``on``: set/clear a breakpoint on a state path), ``pause`` (stop at the next state
  entered), ``continue`` (``path`` optional: release that paused state, or all, and stop pausing),
  ``step`` (``path``: release it and stop at the next state entered), ``force`` (``path``, ``outcome``).
* ``<server>/smach/debug/status`` (latched, on every change): ``{"allowed", "init_allowed", "breakpoints",
  "pausing", "paused": [{"path", "outcomes", "since", "userdata", "userdata_notes"}], "states", "last",
  "caps"}``; with debugging off only ``{"allowed": false, "init_allowed", "reason"}``.

The userdata of a paused state's container is sent as JSON, bounded: keys in ``exclude_keys`` are left
out, a value whose JSON exceeds ``max_value_chars`` is replaced by a note, and at most ``max_total_chars``
are sent (the rest noted).
"""
from __future__ import annotations

import json
import threading
import time
from typing import Any, Callable, Iterable, Optional

import smach
from smach_ros.userdata_codec import to_plain

__all__ = ["StateDebugger", "breakpoint_here", "COMMANDS", "MAX_VALUE_CHARS", "MAX_TOTAL_CHARS"]

COMMANDS = ("break", "pause", "continue", "step", "force")
MAX_VALUE_CHARS = 4000    # JSON characters of one userdata value in the inspector
MAX_TOTAL_CHARS = 32000   # JSON characters of one paused state's userdata
POLL_S = 0.1              # how often a paused state checks for a preempt or shutdown
_BREAKPOINT_ATTR = "_smach_ros_breakpoint"


def breakpoint_here(state: smach.State) -> smach.State:
    """Declare a breakpoint in code: the debugger (when allowed) stops on entering ``state``."""
    setattr(state, _BREAKPOINT_ATTR, True)
    return state


def bounded_userdata(data: dict, exclude: Iterable[str] = (), max_value_chars: int = MAX_VALUE_CHARS,
                     max_total_chars: int = MAX_TOTAL_CHARS) -> tuple:
    """(JSON-ready dict, notes): each value as plain JSON data, within the caps; notes say what was left
    out and why."""
    excluded = set(exclude)
    out: dict = {}
    notes: list = []
    total = 0
    for key in sorted(data, key=str):
        if key in excluded:
            notes.append("%s: excluded" % key)
            continue
        try:
            text = json.dumps(to_plain(data[key], max_values=2000))
        except Exception as ex:  # noqa: BLE001 - to_plain is total, json.dumps of its output should be too
            notes.append("%s: not shown (%s)" % (key, ex))
            continue
        if len(text) > max_value_chars:
            notes.append("%s: %d JSON characters, over the %d cap" % (key, len(text), max_value_chars))
            continue
        if total + len(text) > max_total_chars:
            notes.append("%s: not shown, the userdata is over the %d-character cap" % (key, max_total_chars))
            continue
        total += len(text)
        out[str(key)] = json.loads(text)
    return out, notes


class _Paused:
    """A state held on entry, and what it was told to do."""

    def __init__(self, path: str, outcomes: list, container: smach.Container) -> None:
        self.path = path
        self.outcomes = outcomes
        self.container = container
        self.since = time.time()
        self.action: Optional[str] = None   # 'run' or 'force'
        self.outcome: Optional[str] = None


class StateDebugger:
    """Breakpoints, pause/step and forced outcomes for one tree. ``publish(text)`` sends the status JSON."""

    def __init__(self, root: smach.State, root_path: str, publish: Callable[[str], None],
                 breakpoints: Iterable[str] = (), exclude_keys: Iterable[str] = (),
                 max_value_chars: int = MAX_VALUE_CHARS, max_total_chars: int = MAX_TOTAL_CHARS,
                 is_shutdown: Callable[[], bool] = lambda: False, extra_status: Optional[dict] = None) -> None:
        self._publish = publish
        self._publish_lock = threading.Lock()   # status computed and sent as one step (see publish_status)
        self._extra = dict(extra_status or {})  # facts about the server the viewer shows (init_allowed)
        self._exclude = tuple(exclude_keys)
        self._caps = {"value_chars": max_value_chars, "total_chars": max_total_chars}
        self._is_shutdown = is_shutdown
        self._cond = threading.Condition()
        self._states: dict = {}          # path -> (state, parent container)
        self._wrapped: list = []         # states whose execute we replaced
        self._collect(root, root_path)
        self._breakpoints = set(breakpoints) | {p for p, (s, _) in self._states.items()
                                                if getattr(s, _BREAKPOINT_ATTR, False)}
        unknown = self._breakpoints - set(self._states)
        self._breakpoints -= unknown
        self._pausing = False
        self._paused: dict = {}
        self._last: dict = {"ok": True, "error": "unknown breakpoint paths ignored: %s" % sorted(unknown)} \
            if unknown else {}
        self._active = True

    # ---- instrumentation ------------------------------------------------------------------------
    def _collect(self, container: smach.State, path: str) -> None:
        if not isinstance(container, smach.Container):
            return
        for label, child in container.get_children().items():
            child_path = path.rstrip("/") + "/" + label
            self._states[child_path] = (child, container)
            self._collect(child, child_path)

    def install(self) -> None:
        """Wrap every state's execute (instance attribute; the class's method stays untouched)."""
        for path, (state, container) in self._states.items():
            original = state.execute

            def execute(ud: Any = None, _original: Callable = original, _path: str = path,
                        _state: smach.State = state, _container: smach.Container = container) -> Any:
                forced = self.on_enter(_path, _state, _container)
                if forced is not None:
                    return forced
                return _original(ud) if ud is not None else _original()

            state.execute = execute
            self._wrapped.append(state)
        self.publish_status()

    def uninstall(self) -> None:
        """Restore the states' own execute and release every paused state."""
        with self._cond:
            self._active = False
            for paused in self._paused.values():
                paused.action = paused.action or "run"
            self._cond.notify_all()
        for state in self._wrapped:
            state.__dict__.pop("execute", None)
        self._wrapped = []

    # ---- the hook -------------------------------------------------------------------------------
    def on_enter(self, path: str, state: smach.State, container: smach.Container) -> Optional[str]:
        """Called as ``path`` is entered: returns a forced outcome, or None to run the state."""
        with self._cond:
            if not self._active or not (self._pausing or path in self._breakpoints):
                return None
            paused = _Paused(path, [str(o) for o in state.get_registered_outcomes()], container)
            self._paused[path] = paused
            self._pausing = False  # a pause/step stops once, at the first state entered
        self.publish_status()
        try:
            with self._cond:
                while paused.action is None:
                    if self._is_shutdown() or state.preempt_requested():
                        paused.action = "run"   # let the state see and service its preempt
                        break
                    self._cond.wait(POLL_S)
        finally:
            with self._cond:
                if self._paused.get(path) is paused:
                    del self._paused[path]
            self.publish_status()
        return paused.outcome if paused.action == "force" else None

    # ---- commands -------------------------------------------------------------------------------
    def handle_command(self, text: str) -> None:
        """Apply one JSON command; the outcome (ok or an error) goes out in the status's ``last``."""
        try:
            cmd = json.loads(text)
            if not isinstance(cmd, dict):
                raise ValueError("a command is a JSON object")
            error = self._apply(cmd)
        except (ValueError, TypeError) as ex:
            cmd, error = {}, "bad command: %s" % ex
        with self._cond:
            self._last = {"id": cmd.get("id") if isinstance(cmd, dict) else None, "cmd": cmd.get("cmd"),
                          "ok": not error, "error": error}
        self.publish_status()

    def _apply(self, cmd: dict) -> str:
        name = cmd.get("cmd")
        path = cmd.get("path")
        with self._cond:
            if name == "break":
                if path not in self._states:
                    return "no state %r in this tree" % (path,)
                if cmd.get("on", True):
                    self._breakpoints.add(path)
                else:
                    self._breakpoints.discard(path)
            elif name == "pause":
                self._pausing = True
            elif name in ("continue", "step"):
                targets = [path] if path else list(self._paused)
                if path and path not in self._paused:
                    return "%r is not paused" % (path,)
                self._pausing = name == "step"
                for target in targets:
                    self._paused[target].action = "run"
            elif name == "force":
                paused = self._paused.get(path)
                if paused is None:
                    return "%r is not paused" % (path,)
                outcome = cmd.get("outcome")
                if outcome not in paused.outcomes:
                    return "%r is not an outcome of %s (%s)" % (outcome, path, paused.outcomes)
                paused.outcome, paused.action = outcome, "force"
            else:
                return "unknown command %r (known: %s)" % (name, ", ".join(COMMANDS))
            self._cond.notify_all()
        return ""

    # ---- status ---------------------------------------------------------------------------------
    def status(self) -> dict:
        with self._cond:
            paused = list(self._paused.values())
            out = {**self._extra, "allowed": True, "breakpoints": sorted(self._breakpoints), "pausing": self._pausing,
                   "states": sorted(self._states), "last": dict(self._last), "caps": dict(self._caps),
                   "excluded_keys": list(self._exclude), "paused": []}
        for p in sorted(paused, key=lambda p: p.path):
            ud = p.container.userdata
            with ud._lock:
                data = dict(ud._data)
            shown, notes = bounded_userdata(data, self._exclude, self._caps["value_chars"],
                                            self._caps["total_chars"])
            out["paused"].append({"path": p.path, "outcomes": p.outcomes, "since": p.since,
                                  "userdata": shown, "userdata_notes": notes})
        return out

    def publish_status(self) -> None:
        """Send the status; computing and sending are one step, so the last status sent is the newest.

        Why: two paused children resumed together each publish as they leave; unserialised, the one that
        computed first (still listing the other as paused) could send last, and the viewer showed a state
        paused that had run on (a fresh-clone make test: concurrent children still 'paused' after continue)."""
        with self._publish_lock:
            self._publish(json.dumps(self.status()))
