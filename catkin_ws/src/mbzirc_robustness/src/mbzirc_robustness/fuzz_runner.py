"""Sends the fuzzer's malformed messages and requests to every input of a live graph and checks survival.

Why: a node that dies on a NaN or an empty image ends a mission; this runner finds such nodes
automatically (every subscribed topic, every action goal topic, every service), says which input killed
which node, and collects the error lines each node logged (to check it says clearly what was wrong).

Wall-clock sleeps only: it must work under ``/use_sim_time`` even when nothing publishes ``/clock``.
"""
from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import genpy
import rosgraph
import rospy
import rosservice
from rosgraph_msgs.msg import Log

from mbzirc_robustness import constants as C
from mbzirc_robustness import graph as G
from mbzirc_robustness.fuzz import (SMACH_INIT_TYPE, FuzzCase, generate_cases, message_class, pickle_cases,
                                    pickle_marker_path, populated, serialize)
from mbzirc_robustness.probes import Probe, ProbeRunner
from mbzirc_robustness.report import FuzzReport


# One raw publisher per topic for the life of the process, never unregistered: after an unregister, rospy
# subscribers keep reconnecting to us once a second and each attempt logs a long warning on our side.
_PUBLISHERS: dict[str, rospy.Publisher] = {}


def raw_message_class(cls: type) -> type:
    """A message class with ``cls``'s type and md5 whose ``serialize`` writes pre-made bytes.

    .. note:: rospy keeps one publisher implementation per topic, so all cases of a topic (typed and
       byte garbage alike) go through this one class.
    """

    class RawMessage(genpy.Message):
        __slots__ = ["payload"]
        _slot_types = ["uint8[]"]
        _type = cls._type
        _md5sum = cls._md5sum
        _full_text = cls._full_text
        _has_header = False

        def __init__(self, payload: bytes = b"") -> None:  # noqa: D107
            self.payload = payload

        def serialize(self, buff) -> None:  # noqa: D102
            buff.write(self.payload)

        def deserialize(self, str_):  # noqa: D102 - only responses are deserialized, never this
            self.payload = bytes(str_)
            return self

    return RawMessage


def raw_service_class(srv_cls: type) -> type:
    """A service class with ``srv_cls``'s type/md5, a raw request and the real response class."""
    return type("RawService", (), {"_type": srv_cls._type, "_md5sum": srv_cls._md5sum,
                                   "_request_class": raw_message_class(srv_cls._request_class),
                                   "_response_class": srv_cls._response_class})


@dataclass
class _LogSink:
    """Collects /rosout lines of the target nodes, tagged with the input being fuzzed when they came."""

    nodes: set[str]
    current: str = ""
    lines: list[dict[str, Any]] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def __call__(self, msg: Log) -> None:
        if msg.name not in self.nodes or msg.level < C.WARN_LEVEL:
            return
        with self.lock:
            self.lines.append({"node": msg.name, "level": int(msg.level), "msg": msg.msg[:300],
                               "during": self.current})


class GraphFuzzer:
    """Fuzzes every input of the chosen nodes of the running graph; ``run()`` returns a ``FuzzReport``.

    Args:
        target_nodes: node name patterns (empty: every node but the fuzzer and rosout).
        max_cases: malformed inputs per topic or service.
        rate_hz: messages per second on each topic.
        seed: the generator's seed (same seed, same inputs).
        exclude_*: name patterns never to fuzz.
        call_timeout: a service call that takes longer is reported as hung.
        exclude_cases: ``"<input>: <case label>"`` patterns never sent (a known fatal input of a library,
            so that the rest of that input is still fuzzed).
        probes: functional checks (probes.Probe) run before fuzzing (a probe that fails then is reported
            and not used) and after each fuzzed input on the nodes behind it: the node must still turn a
            valid input into a valid output, not only answer getPid.
        stress: after the malformed cases of a topic, valid but abusive traffic: a flood (C.FLOOD_COUNT
            valid messages at once), on action goal topics a goal storm and goal/cancel races, on action
            result topics spoofed results (valid results of goals nobody sent).
        fuzz_clock: at the end, one /clock message 10 s in the past, then every probe again.
    """

    def __init__(self, target_nodes: list[str] | None = None, max_cases: int = C.DEFAULT_MAX_CASES,
                 rate_hz: float = C.DEFAULT_RATE_HZ, seed: int = 0,
                 exclude_nodes: list[str] | None = None, exclude_topics: list[str] | None = None,
                 exclude_services: list[str] | None = None,
                 call_timeout: float = C.SERVICE_CALL_TIMEOUT_S, exclude_cases: list[str] | None = None,
                 probes: list[Probe] | None = None, stress: bool = True, fuzz_clock: bool = False) -> None:
        self.target_nodes = list(target_nodes or [])
        self.max_cases = max_cases
        self.period = 1.0 / max(rate_hz, 0.1)
        self.seed = seed
        self.exclude_nodes = list(exclude_nodes if exclude_nodes is not None else C.DEFAULT_EXCLUDE_NODES)
        self.exclude_topics = list(exclude_topics if exclude_topics is not None else C.DEFAULT_EXCLUDE_TOPICS)
        self.exclude_services = list(exclude_services if exclude_services is not None
                                     else C.DEFAULT_EXCLUDE_SERVICES)
        self.call_timeout = call_timeout
        self.exclude_cases = list(exclude_cases or [])
        self.probes = list(probes or [])
        self.stress = stress
        self.fuzz_clock = fuzz_clock
        self.prober: ProbeRunner | None = None
        self.me = rospy.get_name()
        self.master = rosgraph.Master(self.me)
        self.my_uri = rospy.get_node_uri() or ""

    # -----------------------------------------------------------------------------------------------
    def targets(self) -> list[G.Target]:
        """The inputs to fuzz now (the graph is read at each call)."""
        nodes, types = G.query_graph(self.master, self.me)
        return G.select_targets(nodes, types, self.target_nodes, self.exclude_nodes, self.exclude_topics,
                                self.exclude_services, self.me)

    def run(self) -> FuzzReport:
        """Fuzz every target once; liveness is checked after every input so a death is attributed."""
        targets = self.targets()
        nodes = sorted({n for t in targets for n in t.nodes})
        report = FuzzReport()
        for n in nodes:
            report.add_node(n, G.query_pid(self.master, n, self.me))
        sink = self._sink = _LogSink(set(nodes))
        self._garbage: list = []
        sub = rospy.Subscriber("/rosout", Log, sink, queue_size=500)
        time.sleep(0.5)  # let /rosout publishers connect to us
        self._baseline(report)
        done: set[tuple[str, str]] = set()
        try:
            for _ in range(C.DISCOVERY_PASSES):
                todo = [tg for tg in targets if (tg.kind, tg.name) not in done
                        and all(n in report.nodes for n in tg.nodes)]
                if not todo or rospy.is_shutdown():
                    break
                for tg in todo:
                    done.add((tg.kind, tg.name))
                    self._fuzz_one(tg, report, sink)
                    self._probe(tg.nodes, report, tg.name)
                targets = self.targets()  # inputs created while we fuzzed (lazy subscribers)
            self._send_garbage(report)
            if self.fuzz_clock and not rospy.is_shutdown():
                self._clock_jump(report, nodes)
            time.sleep(C.SETTLE_S)
            for n in nodes:
                if report.nodes[n]["alive"]:
                    report.set_pid_after(n, G.query_pid(self.master, n, self.me), "end of fuzzing")
        finally:
            sub.unregister()
        with sink.lock:
            for line in sink.lines:
                report.add_log(line)
        return report

    def _cases(self, tg: G.Target, cls: type) -> list[FuzzCase]:
        cases = generate_cases(cls, self.max_cases, seed=self.seed + _stable_hash(tg.name))
        if tg.type == SMACH_INIT_TYPE:
            cases = self._pickle_cases(tg, cls) + cases
        return [c for c in cases if not G.matches(f"{tg.name}: {c.label}", self.exclude_cases)]

    # ---- SMACH introspection: crafted pickles ------------------------------------------------------
    def _marker(self) -> str:
        return pickle_marker_path(str(os.getpid()))

    def _pickle_cases(self, tg: G.Target, cls: type) -> list[FuzzCase]:
        """Crafted pickles for an introspection server's ``container_init``, addressed to its root container
        (read from its ``container_structure``, published every 2 s): with a wrong path the server would
        refuse the command before it ever reads the pickle."""
        from smach_msgs.msg import SmachContainerStructure
        structure = tg.name[: -len("container_init")] + "container_structure"
        try:
            path = rospy.wait_for_message(structure, SmachContainerStructure, timeout=C.STRUCTURE_TIMEOUT_S).path
        except (rospy.ROSException, rospy.ROSInterruptException):
            self._report.add_skipped(f"{tg.name}: crafted pickles", f"no {structure} within "
                                     f"{C.STRUCTURE_TIMEOUT_S:.0f} s: container path unknown")
            return []
        if os.path.exists(self._marker()):
            os.remove(self._marker())
        return pickle_cases(cls, path, self._marker())

    def _check_no_code_ran(self, tg: G.Target, report: FuzzReport, labels: list[str]) -> None:
        """After the crafted pickles: the file their code would create must not exist."""
        if not any(lab.startswith("pickle: ") for lab in labels):
            return
        ran = os.path.exists(self._marker())
        for n in tg.nodes:
            report.add_function_check(n, f"{tg.name}: crafted pickles", "runs no code from a pickle", not ran,
                                      f"{self._marker()} was created: a pickle's code ran" if ran else "ok")

    def _fuzz_one(self, tg: G.Target, report: FuzzReport, sink: _LogSink) -> None:
        if rospy.is_shutdown():
            return
        alive = [n for n in tg.nodes if report.nodes[n]["alive"]]
        if not alive:
            report.add_skipped(tg.name, "every node behind it already died")
            return
        sink.current = tg.name
        rospy.loginfo("fuzzing %s %s (%s) -> %s", tg.kind, tg.name, tg.type or "?", ", ".join(alive))
        if tg.kind == G.KIND_SERVICE:
            self._fuzz_service(tg, report)
        else:
            self._fuzz_topic(tg, report)

    # ---- function ------------------------------------------------------------------------------------
    def _baseline(self, report: FuzzReport) -> None:
        """Run every probe once before fuzzing; keep those that pass (a probe that fails on a fresh node
        is a wrong probe, not a finding), report the others."""
        if not self.probes:
            return
        self.prober = ProbeRunner(self.probes)
        time.sleep(1.0)                                   # let the probe publishers / subscribers connect
        good = []
        for p in self.probes:
            ok, why = False, ''
            for _ in range(3):
                ok, why = self.prober.run(p)
                if ok:
                    break
            if ok:
                good.append(p)
            else:
                report.add_skipped(f"probe {p.node}: {p.describe()}", f"fails before any fuzzing: {why}")
        self.prober.probes = good

    def _probe(self, nodes: list[str], report: FuzzReport, during: str) -> None:
        """After an input was fuzzed: every probe of the (still alive) nodes behind it."""
        if self.prober is None:
            return
        for n in nodes:
            if n not in report.nodes or not report.nodes[n]["alive"]:
                continue
            for p in self.prober.for_node(n):
                ok, why = self.prober.run(p)
                if not ok:                                # one more chance: a busy node may be late once
                    ok, why = self.prober.run(p)
                report.add_function_check(n, during, p.describe(), ok, why)

    def _clock_jump(self, report: FuzzReport, nodes: list[str]) -> None:
        """One /clock message 10 s in the past (a simulator restart, a bag with --clock), then every probe."""
        from rosgraph_msgs.msg import Clock
        pub = _PUBLISHERS.get("/clock")
        if pub is None:
            pub = rospy.Publisher("/clock", raw_message_class(Clock), queue_size=10)
            _PUBLISHERS["/clock"] = pub
        time.sleep(C.CONNECT_TIMEOUT_S)
        now = rospy.get_time()
        pub.publish(pub.data_class(serialize(Clock(clock=rospy.Time.from_sec(max(now - 10.0, 0.001))))))
        time.sleep(1.0)
        report.add_input(G.KIND_TOPIC, "/clock", "rosgraph_msgs/Clock", nodes, 1,
                         labels=["clock: one message 10 s in the past"])
        self._probe(nodes, report, "/clock: one message 10 s in the past")

    def _stress_cases(self, tg: G.Target, cls: type) -> list[tuple[str, str, list[bytes]]]:
        """(label, topic, payloads) of valid but abusive traffic for one topic (see ``stress``)."""
        out: list[tuple[str, str, list[bytes]]] = []
        try:
            template = populated(cls)
            out.append((f"flood: {C.FLOOD_COUNT} valid messages at once", tg.name,
                        [serialize(template)] * C.FLOOD_COUNT))
        except Exception:  # noqa: BLE001 - a type we cannot populate gets no stress cases
            return out
        if tg.kind == G.KIND_ACTION_GOAL and hasattr(template, "goal_id"):
            storm = []
            for k in range(C.GOAL_STORM):
                template.goal_id.id = f"storm-{k}"
                storm.append(serialize(template))
            out.append((f"goal storm: {C.GOAL_STORM} goals at once", tg.name, storm))
            from actionlib_msgs.msg import GoalID
            cancel = tg.name[: -len("/goal")] + "/cancel"
            for k in range(C.PREEMPT_RACES):
                template.goal_id.id = f"race-{k}"
                out.append((f"preempt race {k}: goal then its cancel at once", "", [serialize(template)]))
                out.append((f"preempt race {k}: cancel", cancel, [serialize(GoalID(id=f"race-{k}"))]))
        if tg.name.endswith("/result") and hasattr(template, "status"):
            spoofs = []
            for k in range(5):
                template.status.goal_id.id = f"spoofed-{k}"
                template.status.status = 3            # SUCCEEDED, of a goal nobody sent
                spoofs.append(serialize(template))
            out.append(("spoofed results: 5 valid results of goals never sent", tg.name, spoofs))
        return out

    def _send_stress(self, tg: G.Target, cls: type, pub: rospy.Publisher) -> tuple[int, list[str]]:
        """Send the stress cases of a topic; returns (messages sent, labels)."""
        sent, labels = 0, []
        for label, topic, payloads in self._stress_cases(tg, cls):
            if rospy.is_shutdown():
                break
            target = pub if topic in ("", tg.name) else self._raw_publisher(topic, "actionlib_msgs/GoalID")
            for payload in payloads:
                target.publish(target.data_class(payload))
                sent += 1
            labels.append(label)
            if not label.startswith("preempt race"):
                time.sleep(C.SETTLE_S)
            self._check(tg, report_ref(self), label)
        return sent, labels

    def _raw_publisher(self, topic: str, type_name: str) -> rospy.Publisher:
        pub = _PUBLISHERS.get(topic)
        if pub is None:
            pub = rospy.Publisher(topic, raw_message_class(message_class(type_name)), queue_size=C.DEFAULT_MAX_CASES)
            _PUBLISHERS[topic] = pub
            time.sleep(0.5)
        return pub

    # -----------------------------------------------------------------------------------------------
    def _check(self, tg: G.Target, report: FuzzReport, label: str) -> None:
        """Record a death (no answer, or a new pid after a respawn) of any node behind ``tg``."""
        for n in tg.nodes:
            if report.nodes[n]["alive"]:
                pid = G.query_pid(self.master, n, self.me, timeout=1.0)
                if pid is None:  # a busy node on a loaded machine can miss a 1 s deadline: ask again, patiently
                    time.sleep(0.5)
                    pid = G.query_pid(self.master, n, self.me, timeout=C.XMLRPC_TIMEOUT_S * 2)
                old = report.nodes[n]["pid_before"]
                hung = pid is None and old is not None and os.path.exists(f"/proc/{old}")
                report.set_pid_after(n, pid, f"{tg.name}: {label}"
                                     + (" (process still there but not answering: hung)" if hung else ""))

    def _wait_connected(self, tg: G.Target, pub: rospy.Publisher) -> list[str]:
        """Nodes behind ``tg`` that connected to our publisher (per their own getBusInfo)."""
        deadline = time.monotonic() + C.CONNECT_TIMEOUT_S
        connected: set[str] = set()
        while time.monotonic() < deadline and not rospy.is_shutdown():
            for n in tg.nodes:
                peers = G.inbound_peers(G.query_bus_info(self.master, n, self.me), tg.name)
                if n not in connected and (self.me in peers or self.my_uri in peers):
                    connected.add(n)
            if len(connected) == len(tg.nodes) and pub.get_num_connections() >= len(tg.nodes):
                break
            time.sleep(0.1)
        return sorted(connected)

    def _fuzz_topic(self, tg: G.Target, report: FuzzReport) -> None:
        try:
            cls = message_class(tg.type)
        except Exception as exc:  # noqa: BLE001 - a type we cannot load is reported, not fatal
            report.add_skipped(tg.name, f"cannot load message type {tg.type}: {exc}")
            return
        self._report = report
        cases = self._cases(tg, cls)
        pub = _PUBLISHERS.get(tg.name)
        if pub is None or pub.type != tg.type:
            pub = rospy.Publisher(tg.name, raw_message_class(cls), queue_size=C.DEFAULT_MAX_CASES)
            _PUBLISHERS[tg.name] = pub
        connected = self._wait_connected(tg, pub)
        typed, garbage = [c for c in cases if c.typed], [c for c in cases if not c.typed]
        sent = self._send_cases(tg, report, pub, typed)
        labels = [c.label for c in typed]
        self._check_no_code_ran(tg, report, labels)
        if self.stress and not rospy.is_shutdown() and any(report.nodes[n]["alive"] for n in tg.nodes):
            n_stress, stress_labels = self._send_stress(tg, cls, pub)
            sent += n_stress
            labels += stress_labels
        report.add_input(tg.kind, tg.name, tg.type, tg.nodes, sent, connected=connected, labels=labels)
        # byte garbage at the very end of the run (_send_garbage): a rospy subscriber drops our connection at
        # the first message it cannot deserialize and never hears from us again (probe_sender.py), so
        # anything sent after it on that topic (this topic's stress, another goal's cancel race) would be lost
        self._garbage.append((tg, pub, garbage, report.inputs[-1]))

    def _send_garbage(self, report: FuzzReport) -> None:
        """Every topic's byte garbage, each followed by the probes of the nodes behind it."""
        for tg, pub, garbage, entry in self._garbage:
            if rospy.is_shutdown() or not any(report.nodes[n]["alive"] for n in tg.nodes):
                continue
            self._sink.current = tg.name
            entry["sent"] += self._send_cases(tg, report, pub, garbage)
            entry["labels"] += [c.label for c in garbage]
            self._probe(tg.nodes, report, f"{tg.name}: byte garbage")
        self._garbage = []

    def _send_cases(self, tg: G.Target, report: FuzzReport, pub: rospy.Publisher, cases: list[FuzzCase]) -> int:
        """Publish ``cases`` at the fuzz rate, liveness checked every C.CHECK_EVERY and after the last."""
        sent = 0
        for case in cases:
            if rospy.is_shutdown():
                break
            pub.publish(pub.data_class(case.payload))
            sent += 1
            time.sleep(self.period)
            if sent % C.CHECK_EVERY == 0:
                self._check(tg, report, _window_label(cases, sent))
        if cases:
            time.sleep(C.SETTLE_S)
            self._check(tg, report, _window_label(cases, sent) + " (found after the last case)")
        return sent

    def _fuzz_service(self, tg: G.Target, report: FuzzReport) -> None:
        try:
            tg.type = rosservice.get_service_type(tg.name) or ""
            srv_cls = genpy.message.get_service_class(tg.type)
            if srv_cls is None:
                raise ValueError("unknown service type")
        except Exception as exc:  # noqa: BLE001
            report.add_skipped(tg.name, f"cannot load service type {tg.type!r}: {exc}")
            return
        cases = self._cases(tg, srv_cls._request_class)
        proxy = rospy.ServiceProxy(tg.name, raw_service_class(srv_cls))
        outcomes: list[tuple[str, str]] = []
        for case in cases:
            if rospy.is_shutdown():
                break
            outcome = self._call(proxy, case)
            outcomes.append((case.label, outcome))
            if len(outcomes) % C.CHECK_EVERY == 0 or outcome == "timeout" or len(outcomes) == len(cases):
                self._check(tg, report, _window_label(cases, len(outcomes)))
            if sum(1 for _, o in outcomes if o == "timeout") >= C.MAX_SERVICE_TIMEOUTS:
                break  # the server looks hung: do not pile up blocked calls
        report.add_input(G.KIND_SERVICE, tg.name, tg.type, tg.nodes, len(outcomes), outcomes=outcomes,
                         labels=[c.label for c in cases])

    def _call(self, proxy: rospy.ServiceProxy, case: FuzzCase) -> str:
        """'ok: <response>' / 'error: <why>' / 'timeout' for one request (called in a daemon thread)."""
        result: list[str] = []

        def call() -> None:
            try:
                resp = proxy.call(proxy.request_class(case.payload))
                result.append("ok: " + str(resp).replace("\n", " ")[:200])
            except Exception as exc:  # noqa: BLE001 - every failure is an outcome to report
                result.append(f"error: {type(exc).__name__}: {str(exc)[:200]}")

        th = threading.Thread(target=call, daemon=True)
        th.start()
        th.join(self.call_timeout)
        return result[0] if result else "timeout"


def report_ref(fuzzer: GraphFuzzer) -> FuzzReport:
    """The report being filled (set by ``_fuzz_topic`` before the stress cases)."""
    return fuzzer._report


def _window_label(cases: list[FuzzCase], sent: int) -> str:
    """The cases that may have killed a node found dead after ``sent`` cases (the last CHECK_EVERY)."""
    window = [c.label for c in cases[max(0, sent - C.CHECK_EVERY):sent]]
    return " | ".join(window) if window else "before any case"


def _stable_hash(name: str) -> int:
    """A per-input seed offset that does not change between runs (``hash()`` of str does)."""
    return sum((i + 1) * ord(ch) for i, ch in enumerate(name)) % 100_003
