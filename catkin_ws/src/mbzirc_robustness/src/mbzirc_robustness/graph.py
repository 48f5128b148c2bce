"""What a live ROS graph offers to a fuzzer: each node's subscribed topics and served services.

Why: the fuzzer must find every input of every node without a hand-written list, so that nodes added
by other packages later are fuzzed too. The master's ``getSystemState`` gives the graph; a node's own
``getBusInfo`` tells whether it actually connected to us; ``getPid`` tells whether it is alive.
The parsing and selection functions are pure (tested without a master); the ``query_*`` ones talk XML-RPC.
"""
from __future__ import annotations

import fnmatch
import socket
import xmlrpc.client
from dataclasses import dataclass, field
from typing import Iterable

from mbzirc_robustness import constants as C

KIND_TOPIC = "topic"
KIND_ACTION_GOAL = "action_goal"
KIND_ACTION_CANCEL = "action_cancel"
KIND_SERVICE = "service"


@dataclass
class NodeIO:
    """The inputs of one node: topics it subscribes to and services it serves."""

    name: str
    subscriptions: list[str] = field(default_factory=list)
    services: list[str] = field(default_factory=list)


@dataclass
class Target:
    """One input to fuzz: a topic (with every node subscribed to it) or a service (with its server)."""

    kind: str
    name: str
    type: str
    nodes: list[str]


def parse_system_state(state: list, topic_types: Iterable[tuple[str, str]]) -> tuple[dict[str, NodeIO], dict[str, str]]:
    """Per-node inputs from the master's ``getSystemState`` answer ``[pubs, subs, srvs]``.

    Returns:
        (nodes by name, topic type by topic name).
    """
    _pubs, subs, srvs = state
    nodes: dict[str, NodeIO] = {}
    for topic, names in subs:
        for n in names:
            nodes.setdefault(n, NodeIO(n)).subscriptions.append(topic)
    for srv, names in srvs:
        for n in names:
            nodes.setdefault(n, NodeIO(n)).services.append(srv)
    for io_ in nodes.values():
        io_.subscriptions.sort()
        io_.services.sort()
    return nodes, dict(topic_types)


def topic_kind(topic: str, type_name: str) -> str:
    """Action goal / cancel topics are reported as actions; everything else as a plain topic."""
    if topic.endswith("/goal") and type_name.endswith("ActionGoal"):
        return KIND_ACTION_GOAL
    if topic.endswith("/cancel") and type_name == "actionlib_msgs/GoalID":
        return KIND_ACTION_CANCEL
    return KIND_TOPIC


def matches(name: str, patterns: Iterable[str]) -> bool:
    """fnmatch against any of ``patterns`` (``*/get_loggers``, ``/mbzirc2020_1/*``)."""
    return any(fnmatch.fnmatchcase(name, p) for p in patterns)


def select_targets(nodes: dict[str, NodeIO], topic_types: dict[str, str], target_nodes: Iterable[str] = (),
                   exclude_nodes: Iterable[str] = C.DEFAULT_EXCLUDE_NODES,
                   exclude_topics: Iterable[str] = C.DEFAULT_EXCLUDE_TOPICS,
                   exclude_services: Iterable[str] = C.DEFAULT_EXCLUDE_SERVICES,
                   self_name: str = "") -> list[Target]:
    """The topics and services to fuzz, each with the target nodes behind it, in a stable order.

    Args:
        target_nodes: node name patterns to fuzz; empty means every node.
        exclude_*: name patterns never to touch (``/clock`` would break sim time for everyone).
        self_name: the fuzzer's own node name, never a target.
    """
    target_nodes = list(target_nodes)
    chosen = {n: io_ for n, io_ in nodes.items()
              if n != self_name and not matches(n, exclude_nodes)
              and (not target_nodes or matches(n, target_nodes))}
    by_topic: dict[str, list[str]] = {}
    out: list[Target] = []
    for n, io_ in sorted(chosen.items()):
        for t in io_.subscriptions:
            if not matches(t, exclude_topics):
                by_topic.setdefault(t, []).append(n)
        for s in io_.services:
            if not matches(s, exclude_services):
                out.append(Target(KIND_SERVICE, s, "", [n]))
    for t, ns in sorted(by_topic.items()):
        ty = topic_types.get(t, "")
        if ty and ty != "*":
            out.append(Target(topic_kind(t, ty), t, ty, sorted(ns)))
    out.sort(key=lambda tg: (tg.kind == KIND_SERVICE, tg.name))
    return out


def inbound_peers(bus_info: list, topic: str) -> set[str]:
    """Caller ids of the peers a node receives ``topic`` from, from its ``getBusInfo`` answer.

    Each entry is ``[connection id, peer (caller id or URI), direction 'i'/'o'/'b', transport, topic, ...]``.
    """
    out = set()
    for entry in bus_info:
        if len(entry) >= 5 and entry[4] == topic and entry[2] in ("i", "b"):
            out.add(str(entry[1]))
    return out


# ---------------------------------------------------------------------------------------------------
# XML-RPC (needs a master)
# ---------------------------------------------------------------------------------------------------
class _TimeoutTransport(xmlrpc.client.Transport):
    """XML-RPC transport with a socket timeout: a hung node must not hang the fuzzer."""

    def __init__(self, timeout: float) -> None:
        super().__init__()
        self._timeout = timeout

    def make_connection(self, host):  # type: ignore[override]
        conn = super().make_connection(host)
        conn.timeout = self._timeout
        return conn


def node_proxy(uri: str, timeout: float = C.XMLRPC_TIMEOUT_S) -> xmlrpc.client.ServerProxy:
    """XML-RPC proxy of a node's slave API with a timeout."""
    return xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout))


def query_graph(master, self_name: str = "") -> tuple[dict[str, NodeIO], dict[str, str]]:
    """``getSystemState`` + ``getTopicTypes`` of a ``rosgraph.Master``, parsed."""
    return parse_system_state(master.getSystemState(), master.getTopicTypes())


def query_pid(master, node: str, caller_id: str = "/robustness_fuzzer",
              timeout: float = C.XMLRPC_TIMEOUT_S) -> int | None:
    """Process id of ``node`` via its slave API, or None when it is unknown or does not answer."""
    try:
        uri = master.lookupNode(node)
        code, _msg, pid = node_proxy(uri, timeout).getPid(caller_id)
        return int(pid) if code == 1 else None
    except (OSError, socket.timeout, xmlrpc.client.Error, Exception):  # noqa: BLE001 - any failure = dead
        return None


def query_bus_info(master, node: str, caller_id: str = "/robustness_fuzzer",
                   timeout: float = C.XMLRPC_TIMEOUT_S) -> list:
    """A node's ``getBusInfo`` list (empty when it does not answer)."""
    try:
        uri = master.lookupNode(node)
        code, _msg, info = node_proxy(uri, timeout).getBusInfo(caller_id)
        return list(info) if code == 1 else []
    except Exception:  # noqa: BLE001 - a node that does not answer has no connections for us
        return []
