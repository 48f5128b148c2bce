"""Functional probes: after each batch of malformed input, does the node still do its job?

Why: a node that survives every bad message but whose periodic thread died, whose lock is held forever or
whose table is full of garbage passes a liveness check (`getPid`) and fails the mission. A probe gives the
node a valid input and checks a valid output:
- `output` only: the topic must be published within `timeout` s (a periodic output: the estimator's tracks,
  the central unit's heartbeat (sent by its decision tick), an agent's data_feed);
- `stimulus` + `output`: valid messages are published, then the output must come. A stimulus is one dict
  or a list of them, sent in order: `{topic, type, yaml}` (a message from YAML of its fields), or
  `{rgbd_facade: <camera namespace>, frame_id: ...}` (a synthetic facade holder seen by a RealSense:
  camera_info, then synchronised colour + depth, stimuli.py);
- `expect` (a text or a list): the output message (its YAML text) must contain every one. `@SEQ@` in a
  stimulus's YAML and in `expect` is replaced by the number of the run, so that an output that merely
  repeats an old state (a periodic line that ignores its input) cannot pass;
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
from typing import Any, Callable, Optional

import yaml

SEQ = "@SEQ@"                  # replaced by the run's number in stimuli and expected texts
STIMULUS_GAP_S = 0.2           # between two groups of a stimulus (camera_info before the images)
POLL_S = 0.05


@dataclass
class Probe:
    """One functional check of one node (see the module docstring)."""
    node: str
    output: str = ''
    stimuli: list[dict[str, Any]] = field(default_factory=list)
    service: str = ''
    request: str = ''
    expect: list[str] = field(default_factory=list)
    timeout: float = 3.0

    @staticmethod
    def from_dict(d: dict[str, Any]) -> "Probe":
        stim = d.get('stimulus') or []
        expect = d.get('expect') or []
        return Probe(node=str(d['node']), output=str(d.get('output', '')),
                     stimuli=[dict(s) for s in (stim if isinstance(stim, list) else [stim])],
                     service=str(d.get('service', '')), request=str(d.get('request', '')),
                     expect=[str(e) for e in (expect if isinstance(expect, list) else [expect])],
                     timeout=float(d.get('timeout', 3.0)))

    def describe(self) -> str:
        wanted = f' with {", ".join(map(repr, self.expect))}' if self.expect else ''
        if self.service:
            return f'{self.service} answers a valid request{wanted}'
        inputs = ', '.join(s.get('topic') or f"RGB-D facade holder on {s.get('rgbd_facade')}" for s in self.stimuli)
        return (f'{inputs} -> ' if inputs else '') + f'{self.output} published{wanted}'


def fill(cls: type, text: str) -> Any:
    """A message of class cls with the fields of YAML `text` (rostopic's convention)."""
    import genpy
    msg = cls()
    args = yaml.safe_load(text) if text else {}
    if args:
        genpy.message.fill_message_args(msg, [args])
    return msg


class RosBus:
    """The probes' access to the live graph: one subscriber per output (rospy, in this process); stimuli
    go out through a sender process of their own (probe_sender.py says why)."""

    def __init__(self) -> None:
        import rospy
        self.rospy = rospy
        self.sender: Any = None

    def subscribe(self, topic: str, callback: Callable[[Callable[[], str]], None]) -> None:
        """Calls ``callback(text)`` per message, ``text()`` giving the message as YAML text (decoded only
        when asked: most probes only count)."""
        from rospy.msg import AnyMsg

        def on_msg(msg: Any) -> None:
            callback(lambda: _any_msg_text(msg))
        self.rospy.Subscriber(topic, AnyMsg, on_msg, queue_size=10)

    def publish(self, topic: str, msg: Any) -> None:
        import base64
        import json
        import subprocess
        import sys
        from mbzirc_robustness.fuzz import serialize
        if self.sender is None or self.sender.poll() is not None:
            self.sender = subprocess.Popen([sys.executable, "-m", "mbzirc_robustness.probe_sender"],
                                           stdin=subprocess.PIPE, text=True)
            self.rospy.on_shutdown(self.close)
        line = json.dumps({"topic": topic, "type": msg._type,
                           "payload": base64.b64encode(serialize(msg)).decode("ascii")})
        self.sender.stdin.write(line + "\n")
        self.sender.stdin.flush()

    def close(self) -> None:
        if self.sender is not None and self.sender.poll() is None:
            self.sender.stdin.close()
            try:
                self.sender.wait(5.0)
            except Exception:  # noqa: BLE001 - it must not outlive us
                self.sender.kill()

    def stamp(self) -> Any:
        return self.rospy.Time.now()


def _any_msg_text(msg: Any) -> str:
    """An AnyMsg decoded with the type its publisher announced, as YAML text ('' if undecodable)."""
    try:
        from mbzirc_robustness.fuzz import message_class
        cls = message_class(msg._connection_header['type'])
        return str(cls().deserialize(msg._buff))
    except Exception:  # noqa: BLE001 - an undecodable output does not contain what the probe expects
        return ''


class WallClock:
    now = staticmethod(time.monotonic)
    sleep = staticmethod(time.sleep)


class ProbeRunner:
    """Runs probes against the graph (default: the live one through rospy, which must be initialised).

    Args:
        bus: publish / subscribe / stamp (RosBus); a unit test passes an in-process one.
        clock: now() / sleep() (wall clock); a unit test passes a simulated one.
    """

    def __init__(self, probes: list[Probe], bus: Any = None, clock: Any = None) -> None:
        self.bus = bus if bus is not None else RosBus()
        self.clock = clock if clock is not None else WallClock()
        self.probes = probes
        self.runs = 0
        self.counts: dict[str, int] = {}
        self.recent: dict[str, list[tuple[int, Callable[[], str]]]] = {}
        self.lock = threading.Lock()
        for topic in {p.output for p in probes if p.output}:
            self.bus.subscribe(topic, lambda text, topic=topic: self._on_output(topic, text))

    def _on_output(self, topic: str, text: Callable[[], str]) -> None:
        with self.lock:
            n = self.counts[topic] = self.counts.get(topic, 0) + 1
            self.recent.setdefault(topic, []).append((n, text))
            del self.recent[topic][:-20]

    def for_node(self, node: str) -> list[Probe]:
        return [p for p in self.probes if p.node == node]

    def run(self, probe: Probe) -> tuple[bool, str]:
        """(passed, what happened) for one probe."""
        self.runs += 1
        expect = [e.replace(SEQ, str(self.runs)) for e in probe.expect]
        if probe.service:
            return self._call(probe, expect)
        with self.lock:
            before = self.counts.get(probe.output, 0)
        try:
            self._send(probe.stimuli)
        except Exception as e:  # noqa: BLE001 - a bad probe definition is the probe's failure
            return False, f'cannot send the stimulus: {e}'
        deadline = self.clock.now() + probe.timeout
        seen = 0
        while True:
            with self.lock:
                new = [text for n, text in self.recent.get(probe.output, []) if n > before]
            for text in new[seen:]:
                if all(e in text() for e in expect):
                    return True, 'ok'
            seen = len(new)
            if self.clock.now() >= deadline:
                break
            self.clock.sleep(POLL_S)
        if seen and expect:
            return False, (f'{probe.output}: {seen} message(s) within {probe.timeout:.1f} s, none with '
                           f'{", ".join(map(repr, expect))}')
        return False, f'{probe.output} not published within {probe.timeout:.1f} s'

    def _send(self, stimuli: list[dict[str, Any]]) -> None:
        """Publish the stimuli in order, a short gap between groups (see the module docstring)."""
        from mbzirc_robustness.fuzz import message_class
        groups: list[list[tuple[str, Any]]] = []
        for s in stimuli:
            if 'rgbd_facade' in s:
                from mbzirc_robustness.stimuli import facade_holder_messages
                groups += facade_holder_messages(str(s['rgbd_facade']), str(s.get('frame_id', '')), self.bus.stamp())
            else:
                text = str(s.get('yaml', '')).replace(SEQ, str(self.runs))
                groups.append([(s['topic'], fill(message_class(s['type']), text))])
        for k, group in enumerate(groups):
            if k:
                self.clock.sleep(STIMULUS_GAP_S)
            for topic, msg in group:
                self.bus.publish(topic, msg)

    def _call(self, probe: Probe, expect: list[str]) -> tuple[bool, str]:
        import genpy
        import rospy
        import rosservice
        out: list[tuple[bool, str]] = []

        def call() -> None:
            try:
                srv_cls = genpy.message.get_service_class(rosservice.get_service_type(probe.service))
                resp = rospy.ServiceProxy(probe.service, srv_cls)(fill(srv_cls._request_class, probe.request))
                text = str(resp)
                ok = all(e in text for e in expect)
                out.append((ok, 'ok' if ok else f'answered {text[:120]!r}, expected {", ".join(map(repr, expect))}'))
            except Exception as e:  # noqa: BLE001 - not answering is the outcome
                out.append((False, f'{type(e).__name__}: {str(e)[:120]}'))

        th = threading.Thread(target=call, daemon=True)
        th.start()
        th.join(probe.timeout)
        return out[0] if out else (False, f'{probe.service} did not answer within {probe.timeout:.1f} s')


def parse_probes(raw: Optional[list]) -> list[Probe]:
    """Probes from the `~probes` rosparam (a list of dicts)."""
    return [Probe.from_dict(d) for d in (raw or [])]
