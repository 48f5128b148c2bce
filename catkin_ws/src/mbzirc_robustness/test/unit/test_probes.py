"""The functional probes of the fuzz rostests can fail: run against in-process nodes on a simulated clock.

The probes are read from the rostest files themselves, so what passes or fails here is what the fuzzer
runs. A node that does its job (the circle detector's own pipeline on the stimulus images, the recorder's
own progress line) passes; a node that does not answer, or answers without using its input, fails.
"""
import json
import os
import xml.etree.ElementTree as ET

import genpy
import pytest
import yaml
from geometry_msgs.msg import PointStamped
from std_msgs.msg import String

from mbzirc_robustness.probes import Probe, ProbeRunner

TEST_DIR = os.path.join(os.path.dirname(__file__), "..")


def launch_probe(test_file: str, node: str) -> Probe:
    """The probe of ``node`` in the ``probes`` rosparam of a fuzz rostest."""
    root = ET.parse(os.path.join(TEST_DIR, test_file)).getroot()
    for rp in root.iter("rosparam"):
        if rp.get("param") == "probes":
            for d in yaml.safe_load(rp.text):
                if d["node"] == node:
                    return Probe.from_dict(d)
    raise LookupError(f"no probe of {node} in {test_file}")


class SimClock:
    """Simulated time: sleeping runs the nodes' periodic work instead of waiting."""

    def __init__(self):
        self.t = 0.0
        self.periodic = []

    def now(self):
        return self.t

    def sleep(self, dt):
        for _ in range(max(1, int(round(dt / 0.05)))):
            self.t += min(dt, 0.05)
            for f in self.periodic:
                f(self.t)


class Bus:
    """In-process topics: publish delivers synchronously to the nodes' and the probes' subscribers."""

    def __init__(self):
        self.probe_subs = {}    # topic -> callbacks of the ProbeRunner (given the message's text)
        self.node_subs = {}     # topic -> callbacks of the fake nodes (given the message)
        self.sent = []

    def subscribe(self, topic, callback):
        self.probe_subs.setdefault(topic, []).append(callback)

    def node_subscribe(self, topic, callback):
        self.node_subs.setdefault(topic, []).append(callback)

    def publish(self, topic, msg):
        self.sent.append(topic)
        for cb in self.node_subs.get(topic, []):
            cb(msg)
        for cb in self.probe_subs.get(topic, []):
            cb(lambda m=msg: str(m))

    def stamp(self):
        return genpy.Time(7, 0)


# ---- circle detector ---------------------------------------------------------------------------------
class CircleDetector:
    """The circle detector's work with its own library (tuned.yaml): camera_info, then colour + depth
    with one stamp -> the middle hole. ``works=False``: it takes its inputs and never answers."""

    def __init__(self, bus, ns, works=True):
        from circle_detector.hough import HoughParams
        import rospkg
        tuned = os.path.join(rospkg.RosPack().get_path("circle_detector"), "config", "tuned.yaml")
        with open(tuned, encoding="utf-8") as f:
            self.params = HoughParams(**yaml.safe_load(f))
        self.bus, self.ns, self.works = bus, ns, works
        self.K, self.images = None, {}
        bus.node_subscribe(f"{ns}/camera/color/camera_info", self.on_info)
        bus.node_subscribe(f"{ns}/camera/color/image_rect_color", lambda m: self.on_image("colour", m))
        bus.node_subscribe(f"{ns}/camera/aligned_depth_to_color/image_raw", lambda m: self.on_image("depth", m))

    def on_info(self, msg):
        from circle_detector.hough import Intrinsics
        self.K = Intrinsics.from_k(list(msg.K), msg.width, msg.height)

    def on_image(self, kind, msg):
        from circle_detector.hole_choice import choose_hole
        from circle_detector.hough import depth_to_metres, detect_circles
        from circle_detector.images import image_to_array
        self.images[kind] = msg
        c, d = self.images.get("colour"), self.images.get("depth")
        if not (self.works and self.K and c and d and c.header.stamp == d.header.stamp):
            return
        bgr = image_to_array(c.height, c.width, c.encoding, c.step, c.is_bigendian, c.data)
        depth = depth_to_metres(image_to_array(d.height, d.width, d.encoding, d.step, d.is_bigendian, d.data),
                                d.encoding)
        circles = detect_circles(bgr, depth, self.K, self.params)
        i = choose_hole([(k.x, k.y, k.z, k.radius_m) for k in circles], [k.opening_m for k in circles])
        if i is not None:
            p = PointStamped()
            p.header = c.header
            p.point.x, p.point.y, p.point.z = circles[i].x, circles[i].y, circles[i].z
            self.bus.publish(f"{self.ns}/circle_detection/middle_hole", p)


@pytest.mark.parametrize("works", [True, False])
def test_circle_detector_probe_passes_only_when_the_hole_is_found(works):
    probe = launch_probe("fuzz_project_nodes.test", "/mbzirc2020_2/circle_detector")
    bus, clock = Bus(), SimClock()
    CircleDetector(bus, "/mbzirc2020_2", works=works)
    runner = ProbeRunner([probe], bus=bus, clock=clock)
    ok, why = runner.run(probe)
    assert ok == works, why
    if not works:
        assert "not published" in why
    assert bus.sent[0].endswith("camera_info"), "camera_info must go before the images"


def test_circle_detector_probe_fails_on_a_hole_elsewhere():
    """An old hole, or one at another place, is not what the stimulus shows."""
    probe = launch_probe("fuzz_project_nodes.test", "/mbzirc2020_2/circle_detector")
    bus, clock = Bus(), SimClock()
    wrong = PointStamped()
    wrong.point.z = 5.5
    bus.node_subscribe("/mbzirc2020_2/camera/aligned_depth_to_color/image_raw",
                       lambda _m: bus.publish("/mbzirc2020_2/circle_detection/middle_hole", wrong))
    ok, why = ProbeRunner([probe], bus=bus, clock=clock).run(probe)
    assert not ok and "none with" in why


# ---- mission recorder --------------------------------------------------------------------------------
class Recorder:
    """The recorder's progress line (its own ``progress_line``) from what it received, once a second.

    ``records=False``: the line keeps coming but the inputs never reach the record (a recorder whose
    callbacks died: alive and periodic, not working)."""

    def __init__(self, bus, clock, records=True):
        from mbzirc_referee.recorder import MissionRecorder
        from mbzirc_referee.summary import MissionRecord
        self.bus, self.records = bus, records
        self.r = MissionRecorder.__new__(MissionRecorder)   # its formatting without its ROS set-up
        self.r.rec, self.r.status, self.r.sim_start_wall = MissionRecord(seed=0, duration=1e12), {}, None
        bus.node_subscribe("/sim/score", self.on_score)
        bus.node_subscribe("/central_unit/status", self.on_status)
        self.next = 1.0
        clock.periodic.append(self.tick)

    def on_score(self, msg):
        if self.records:
            self.r.rec.set_score(msg.elapsed, msg.score, list(msg.crashed_robots))

    def on_status(self, msg):
        if self.records:
            self.r.status = json.loads(msg.data)

    def tick(self, t):
        if t >= self.next:
            self.next += 1.0
            self.bus.publish("/mission_recorder/progress", String(self.r.progress_line()))


@pytest.mark.parametrize("records", [True, False])
def test_recorder_probe_needs_the_fresh_input_in_the_output(records):
    probe = launch_probe("fuzz_ugv_recorder_nodes.test", "/mission_recorder")
    bus, clock = Bus(), SimClock()
    Recorder(bus, clock, records=records)
    runner = ProbeRunner([probe], bus=bus, clock=clock)
    for _ in range(3):                                       # each run must see its own input come out
        ok, why = runner.run(probe)
        assert ok == records, why
    if not records:
        assert "none with" in why, why


def test_recorder_probe_fails_when_the_recorder_is_silent():
    probe = launch_probe("fuzz_ugv_recorder_nodes.test", "/mission_recorder")
    bus, clock = Bus(), SimClock()
    ok, why = ProbeRunner([probe], bus=bus, clock=clock).run(probe)
    assert not ok and "not published" in why


def test_stimulus_and_expect_forms():
    p = Probe.from_dict({"node": "/n", "output": "/o", "expect": "a",
                         "stimulus": {"topic": "/t", "type": "std_msgs/String", "yaml": "{data: x}"}})
    assert p.expect == ["a"] and len(p.stimuli) == 1
    assert "/t -> /o published with 'a'" == p.describe()
