"""The viewer's picture of every introspection server: containers, structure, status and userdata.

Pure Python (no ROS): the ROS adapter feeds it plain fields from SmachContainerStructure/Status
messages; the web server reads JSON snapshots and DOT graphs from it. Thread-safe.
"""
from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Optional

from smach_ros.userdata_codec import DecodeError, decode_local_data, to_plain

__all__ = ["ViewerModel", "ContainerView", "build_dot"]

STALE_AFTER_S = 10.0  # a server silent this long (no heartbeat) is shown as stale
WIDE_CONTAINER_CHILDREN = 8  # a container with more children is laid out left-right
MAX_DEBUG_STATUS_CHARS = 256 * 1024  # a server's debug status is sent to every browser: bounded


@dataclass
class ContainerView:
    """What the viewer knows of one container."""
    path: str
    children: list = field(default_factory=list)
    internal_outcomes: list = field(default_factory=list)
    outcomes_from: list = field(default_factory=list)
    outcomes_to: list = field(default_factory=list)
    container_outcomes: list = field(default_factory=list)
    has_structure: bool = False
    initial_states: list = field(default_factory=list)
    active_states: list = field(default_factory=list)
    userdata: Any = None
    userdata_error: str = ""
    info: str = ""

    def edges(self) -> list:
        return list(zip(self.internal_outcomes, self.outcomes_from, self.outcomes_to))


class ViewerModel:
    """All servers' containers; bumps ``version`` (and ``structure_version`` per server) on changes."""

    def __init__(self, allow_unpickle: bool = False, clock: Callable[[], float] = time.monotonic) -> None:
        self._allow_unpickle = allow_unpickle
        self._clock = clock
        self._lock = threading.Condition()
        self._servers: dict[str, dict[str, ContainerView]] = {}
        self._structure_version: dict[str, int] = {}
        self._last_seen: dict[str, float] = {}
        self._debug: dict[str, dict] = {}  # server -> its last debug status (see smach_ros.debugger)
        self.version = 0

    # ---- updates --------------------------------------------------------------------------------
    def _container(self, server: str, path: str) -> ContainerView:
        containers = self._servers.setdefault(server, {})
        self._structure_version.setdefault(server, 0)
        view = containers.get(path)
        if view is None:
            view = containers[path] = ContainerView(path=path)
            self._structure_version[server] += 1
        return view

    def update_structure(self, server: str, path: str, children: list, internal_outcomes: list,
                         outcomes_from: list, outcomes_to: list, container_outcomes: list) -> bool:
        """Store a structure message; returns True if the structure changed. Inconsistent edge lists are
        rejected with ValueError."""
        if not (len(internal_outcomes) == len(outcomes_from) == len(outcomes_to)):
            raise ValueError("structure of %s%s has edge lists of different lengths" % (server, path))
        if not path.startswith("/"):
            raise ValueError("container path %r must start with '/'" % path)
        new = (list(children), list(internal_outcomes), list(outcomes_from), list(outcomes_to),
               list(container_outcomes))
        with self._lock:
            view = self._container(server, path)
            self._last_seen[server] = self._clock()
            old = (view.children, view.internal_outcomes, view.outcomes_from, view.outcomes_to,
                   view.container_outcomes)
            changed = (not view.has_structure) or old != new
            if changed:
                (view.children, view.internal_outcomes, view.outcomes_from, view.outcomes_to,
                 view.container_outcomes) = new
                view.has_structure = True
                self._structure_version[server] += 1
                self._bump()
            return changed

    def update_status(self, server: str, path: str, initial_states: list, active_states: list,
                      local_data: str, info: str) -> None:
        """Store a status message (userdata decoded safely; undecodable data is reported, not raised)."""
        if not path.startswith("/"):
            raise ValueError("container path %r must start with '/'" % path)
        try:
            userdata = to_plain(decode_local_data(local_data, allow_unsafe=self._allow_unpickle))
            error = ""
        except DecodeError as ex:
            userdata, error = None, str(ex)
        with self._lock:
            view = self._container(server, path)
            self._last_seen[server] = self._clock()
            view.initial_states = list(initial_states)
            view.active_states = list(active_states)
            view.userdata = userdata
            view.userdata_error = error
            view.info = info
            self._bump()

    def update_debug(self, server: str, status_json: str) -> None:
        """Store a server's debug status (JSON text, see smach_ros.debugger); text that is too long or not of
        that shape raises ValueError (it would reach every browser as is)."""
        if len(status_json) > MAX_DEBUG_STATUS_CHARS:
            raise ValueError("debug status of %d characters (cap %d)" % (len(status_json), MAX_DEBUG_STATUS_CHARS))
        status = json.loads(status_json)
        if not isinstance(status, dict) or not isinstance(status.get("allowed"), bool):
            raise ValueError("debug status must be a JSON object with a boolean 'allowed'")
        paused = status.get("paused", [])
        if not isinstance(paused, list) or not isinstance(status.get("breakpoints", []), list) or not all(
                isinstance(p, dict) and isinstance(p.get("path"), str) and isinstance(p.get("outcomes"), list)
                and isinstance(p.get("userdata_notes", []), list) for p in paused):
            raise ValueError("debug status: 'paused' must list {path, outcomes, ...} objects")
        with self._lock:
            self._debug[server] = status
            self._bump()

    def debug(self, server: str) -> Optional[dict]:
        with self._lock:
            return self._debug.get(server)

    def remove_server(self, server: str) -> None:
        with self._lock:
            had_debug = self._debug.pop(server, None) is not None
            if self._servers.pop(server, None) is not None or had_debug:
                self._structure_version.pop(server, None)
                self._last_seen.pop(server, None)
                self._bump()

    def _bump(self) -> None:
        self.version += 1
        self._lock.notify_all()

    def wait_for_change(self, version: int, timeout: float) -> int:
        """Block until ``self.version`` differs from ``version`` (or timeout); returns the new version."""
        with self._lock:
            self._lock.wait_for(lambda: self.version != version, timeout)
            return self.version

    # ---- queries --------------------------------------------------------------------------------
    def servers(self) -> list:
        with self._lock:
            return sorted(self._servers)

    def snapshot(self) -> dict:
        """A JSON-serialisable picture of everything (what the page renders)."""
        with self._lock:
            now = self._clock()
            out = {"version": self.version, "servers": {}}
            for server, containers in sorted(self._servers.items()):
                out["servers"][server] = {
                    "debug": self._debug.get(server),
                    "structure_version": self._structure_version.get(server, 0),
                    "stale": now - self._last_seen.get(server, now) > STALE_AFTER_S,
                    "containers": {
                        path: {"children": list(v.children), "container_outcomes": list(v.container_outcomes),
                               "initial_states": list(v.initial_states), "active_states": list(v.active_states),
                               "userdata": v.userdata, "userdata_error": v.userdata_error, "info": v.info,
                               "has_structure": v.has_structure}
                        for path, v in sorted(containers.items())},
                }
            return out

    def dot(self, server: str, collapsed: Iterable[str] = ()) -> Optional[str]:
        """The DOT graph of ``server``; containers whose path is in ``collapsed`` are drawn as one node."""
        with self._lock:
            containers = self._servers.get(server)
            if not containers:
                return None
            copies = {p: ContainerView(**vars(v)) for p, v in containers.items()}
        return build_dot(server, copies, set(collapsed))


# ---- DOT ------------------------------------------------------------------------------------------
def _q(text: str) -> str:
    """A DOT double-quoted string."""
    return '"' + str(text).replace("\\", "\\\\").replace('"', '\\"').replace("\n", " ") + '"'


def state_id(path: str) -> str:
    return "s:" + path


def cluster_id(path: str) -> str:
    return "c:" + path


def outcome_id(path: str, outcome: str) -> str:
    return "o:" + path + ":" + outcome


def build_dot(server: str, containers: dict, collapsed: Optional[set] = None) -> str:
    """A DOT graph of one server's tree: containers as clusters, states as ellipses, container outcomes
    as boxes; every element carries an ``id`` the page uses to highlight it. A container in ``collapsed``
    is drawn as a single box (id ``s:<path>``, like a state) with every edge of its cluster on it."""
    collapsed = collapsed or set()
    containers = {p: v for p, v in containers.items()
                  if not any(p.startswith(c + "/") for c in collapsed)}  # inside a collapsed one: hidden
    roots = [p for p in containers if p.rsplit("/", 1)[0] not in containers]
    # a container of many states (an agent: one idle state and a state per task) laid out top-down is one
    # very wide row; left-right it becomes a column that fits beside the side panel
    widest = max((len(v.children) for v in containers.values()), default=0)
    rankdir = "LR" if widest > WIDE_CONTAINER_CHILDREN else "TB"
    lines = ["digraph smach {", "  compound=true; rankdir=%s; newrank=true;" % rankdir,
             '  graph [fontname="Helvetica", fontsize=12];', '  node [fontname="Helvetica", fontsize=11];',
             '  edge [fontname="Helvetica", fontsize=9];']
    edges: list[str] = []

    def anchor(path: str) -> Optional[str]:
        """A node inside container ``path`` that edges into it can point at."""
        view = containers.get(path)
        if view is None or not view.has_structure:
            return None
        targets = view.initial_states or view.children
        for label in targets:
            child = path + "/" + label
            if child in collapsed:
                return child
            if child in containers and containers[child].has_structure:
                inner = anchor(child)
                if inner:
                    return inner
            elif label in view.children:
                return child
        if view.container_outcomes:
            return path + ":" + view.container_outcomes[0]
        return None

    def emit(path: str, depth: int) -> None:
        view = containers[path]
        ind = "  " * (depth + 1)
        label = path.rsplit("/", 1)[-1] or path
        lines.append("%ssubgraph %s {" % (ind, _q("cluster_" + path)))
        lines.append("%s  id=%s; label=%s; style=\"rounded\"; color=\"#888888\";"
                     % (ind, _q(cluster_id(path)), _q(label)))
        if not view.has_structure:
            lines.append("%s  %s [id=%s, label=\"(waiting for structure)\", shape=plaintext];"
                         % (ind, _q(path + ":?"), _q("w:" + path)))
        for child in view.children:
            child_path = path + "/" + child
            if child_path in collapsed and child_path in containers:
                lines.append("%s  %s [id=%s, label=%s, shape=box3d, style=filled, fillcolor=\"#ffffff\"];"
                             % (ind, _q(child_path), _q(state_id(child_path)), _q(child + " [+]")))
            elif child_path in containers:
                emit(child_path, depth + 1)
            else:
                lines.append("%s  %s [id=%s, label=%s, shape=ellipse, style=filled, fillcolor=\"#ffffff\"];"
                             % (ind, _q(child_path), _q(state_id(child_path)), _q(child)))
        for outcome in view.container_outcomes:
            lines.append("%s  %s [id=%s, label=%s, shape=box, style=\"rounded,filled\", fillcolor=\"#eeeeee\"];"
                         % (ind, _q(path + ":" + outcome), _q(outcome_id(path, outcome)), _q(outcome)))
        lines.append(ind + "}")
        for outcome, src, dst in view.edges():
            src_path = path + "/" + src
            attrs = ["label=" + _q(outcome)]
            if src_path in collapsed:
                tail = src_path
            elif src_path in containers:
                inner = containers[src_path]
                if outcome in inner.container_outcomes:
                    tail = src_path + ":" + outcome
                else:
                    tail = anchor(src_path)
                    attrs.append("ltail=" + _q("cluster_" + src_path))
            elif src in view.children:
                tail = src_path
            else:
                continue
            if dst in ("None", "") or dst is None:
                dst = outcome
            dst_path = path + "/" + dst
            if dst in view.children:
                if dst_path in collapsed:
                    head = dst_path
                elif dst_path in containers:
                    head = anchor(dst_path)
                    attrs.append("lhead=" + _q("cluster_" + dst_path))
                else:
                    head = dst_path
            elif dst in view.container_outcomes:
                head = path + ":" + dst
            else:
                continue
            if tail is None or head is None:
                continue
            edges.append("  %s -> %s [%s];" % (_q(tail), _q(head), ", ".join(attrs)))

    for root in sorted(roots):
        emit(root, 0)
    lines.extend(edges)
    lines.append("}")
    return "\n".join(lines) + "\n"
