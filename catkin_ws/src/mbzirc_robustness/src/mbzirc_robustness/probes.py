"""Functional probes: after each batch of malformed input, does the node still do its job?

Why: a node that survives every bad message but whose periodic thread died, whose lock is held forever or
whose table is full of garbage passes a liveness check (`getPid`) and fails the mission. A probe gives the
node a valid input and checks a valid output:
- `output` only: the topic must be published within `timeout` s (a periodic output: the estimator's tracks,
  the central unit's heartbeat (sent by its decision tick), an agent's data_feed);
- `stimulus` + `output`: a valid message (YAML of its fields) is published, then the output must come;
- `service` + `request` (+ `expect`): a valid request must be answered, its response containing `expect`.

A probe is a dict (the `~probes` rosparam of the fuzz rostests):
    {node: /object_estimator, output: /estimated_objects, timeout: 3.0,
     stimulus: {topic: /mbzirc2020_1/sensed_objects, type: mbzirc_comm_objs/ObjectDetectionList, yaml: "..."}}
    {node: /region_manager, service: /ask_for_region, request: "{agent_id: '1', ...}", expect: "success: True"}
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any, Optional

import yaml


@dataclass
class Probe:
    """One functional check of one node (see the module docstring)."""
    node: str
    output: str = ''
    stimulus: dict[str, Any] = field(default_factory=dict)
    service: str = ''
    request: str = ''
    expect: str = ''
    timeout: float = 3.0

    @staticmethod
    def from_dict(d: dict[str, Any]) -> "Probe":
        return Probe(node=str(d['node']), output=str(d.get('output', '')), stimulus=dict(d.get('stimulus') or {}),
                     service=str(d.get('service', '')), request=str(d.get('request', '')),
                     expect=str(d.get('expect', '')), timeout=float(d.get('timeout', 3.0)))

    def describe(self) -> str:
        if self.service:
            return f'{self.service} answers a valid request' + (f' with {self.expect!r}' if self.expect else '')
        return (f'{self.stimulus["topic"]} -> ' if self.stimulus else '') + f'{self.output} published'


def fill(cls: type, text: str) -> Any:
    """A message of class cls with the fields of YAML `text` (rostopic's convention)."""
    import genpy
    msg = cls()
    args = yaml.safe_load(text) if text else {}
    if args:
        genpy.message.fill_message_args(msg, [args])
    return msg


class ProbeRunner:
    """Runs probes against the live graph (needs rospy initialised)."""

    def __init__(self, probes: list[Probe]) -> None:
        import rospy
        from rospy.msg import AnyMsg
        self.rospy = rospy
        self.probes = probes
        self.counts: dict[str, int] = {}
        self.lock = threading.Lock()
        self.subs = {}
        self.pubs = {}
        for p in probes:
            if p.output and p.output not in self.subs:
                self.subs[p.output] = rospy.Subscriber(p.output, AnyMsg, self._count, callback_args=p.output,
                                                       queue_size=10)
            if p.stimulus and p.stimulus['topic'] not in self.pubs:
                from mbzirc_robustness.fuzz import message_class
                cls = message_class(p.stimulus['type'])
                self.pubs[p.stimulus['topic']] = (rospy.Publisher(p.stimulus['topic'], cls, queue_size=10), cls)

    def _count(self, _msg: Any, topic: str) -> None:
        with self.lock:
            self.counts[topic] = self.counts.get(topic, 0) + 1

    def for_node(self, node: str) -> list[Probe]:
        return [p for p in self.probes if p.node == node]

    def run(self, probe: Probe) -> tuple[bool, str]:
        """(passed, what happened) for one probe."""
        if probe.service:
            return self._call(probe)
        with self.lock:
            before = self.counts.get(probe.output, 0)
        if probe.stimulus:
            pub, cls = self.pubs[probe.stimulus['topic']]
            try:
                pub.publish(fill(cls, probe.stimulus.get('yaml', '')))
            except Exception as e:  # noqa: BLE001 - a bad probe definition is the probe's failure
                return False, f'cannot send the stimulus: {e}'
        deadline = time.monotonic() + probe.timeout
        while time.monotonic() < deadline:
            with self.lock:
                if self.counts.get(probe.output, 0) > before:
                    return True, 'ok'
            time.sleep(0.05)
        return False, f'{probe.output} not published within {probe.timeout:.1f} s'

    def _call(self, probe: Probe) -> tuple[bool, str]:
        import genpy
        import rosservice
        out: list[tuple[bool, str]] = []

        def call() -> None:
            try:
                srv_cls = genpy.message.get_service_class(rosservice.get_service_type(probe.service))
                resp = self.rospy.ServiceProxy(probe.service, srv_cls)(fill(srv_cls._request_class, probe.request))
                text = str(resp)
                ok = not probe.expect or probe.expect in text
                out.append((ok, 'ok' if ok else f'answered {text[:120]!r}, expected {probe.expect!r}'))
            except Exception as e:  # noqa: BLE001 - not answering is the outcome
                out.append((False, f'{type(e).__name__}: {str(e)[:120]}'))

        th = threading.Thread(target=call, daemon=True)
        th.start()
        th.join(probe.timeout)
        return out[0] if out else (False, f'{probe.service} did not answer within {probe.timeout:.1f} s')


def parse_probes(raw: Optional[list]) -> list[Probe]:
    """Probes from the `~probes` rosparam (a list of dicts)."""
    return [Probe.from_dict(d) for d in (raw or [])]
