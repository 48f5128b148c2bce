"""Tests of the malformed-message generator (pure, no ROS master)."""
import math

import pytest
from geometry_msgs.msg import PoseStamped
from mbzirc_comm_objs.msg import AgentDataFeed, ObjectDetectionList
from mbzirc_comm_objs.srv import AskForRegionRequest, CheckFireRequest, GetCostToGoToRequest
from sensor_msgs.msg import CameraInfo, Image, LaserScan
from std_msgs.msg import Float64MultiArray, Header
from uav_abstraction_layer.srv import GoToWaypointRequest

from mbzirc_robustness import fuzz

CLASSES = [Image, LaserScan, CameraInfo, Float64MultiArray, ObjectDetectionList, AgentDataFeed,
           PoseStamped, Header, CheckFireRequest, AskForRegionRequest, GetCostToGoToRequest,
           GoToWaypointRequest]


def decode(cls, case):
    return cls().deserialize(case.payload)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c._type)
def test_typed_cases_deserialize_and_raw_cases_do_not(cls):
    cases = fuzz.generate_cases(cls, max_cases=40, seed=3)
    assert cases, "no case generated"
    assert len(cases) <= 40
    assert len({c.payload for c in cases}) == len(cases), "duplicate payloads"
    for case in cases:
        if case.typed:
            assert isinstance(decode(cls, case), cls), case.label
    raws = [c for c in cases if not c.typed]
    assert raws, "no raw byte garbage"
    if not cls.__slots__:
        return  # an empty request accepts any bytes
    broken = 0
    for case in raws:
        try:
            cls().deserialize(case.payload)
        except Exception:
            broken += 1
    assert broken >= 1, "at least one raw case must be undeserializable"


def test_same_seed_same_cases_other_seed_other_order():
    a = [c.label for c in fuzz.generate_cases(ObjectDetectionList, seed=1)]
    b = [c.label for c in fuzz.generate_cases(ObjectDetectionList, seed=1)]
    c = [c.label for c in fuzz.generate_cases(ObjectDetectionList, seed=2)]
    assert a == b
    assert a != c


def _floats(msg):
    for lf in fuzz.leaves(msg):
        if lf.base in fuzz.FLOAT_VALUES:
            v = fuzz.get_path(msg, lf.path)
            yield from (v if lf.is_array else [v])


def test_nan_and_inf_reach_the_wire():
    cases = fuzz.generate_cases(PoseStamped, max_cases=60)
    decoded = [decode(PoseStamped, c) for c in cases if c.typed]
    values = [v for m in decoded for v in _floats(m)]
    assert any(math.isnan(v) for v in values)
    assert any(v == math.inf for v in values)
    assert any(v == -math.inf for v in values)
    assert any(abs(v) > 1e300 and math.isfinite(v) for v in values), "no huge finite value"
    all_nan = next(m for m, c in zip(decoded, [c for c in cases if c.typed]) if c.label == "all floats NaN")
    assert all(math.isnan(v) for v in _floats(all_nan))


def test_image_cases_cover_empty_wrong_encoding_and_wrong_size():
    imgs = [decode(Image, c) for c in fuzz.generate_cases(Image) if c.typed]
    assert any(i.height == 0 and i.width == 0 and len(i.data) == 0 for i in imgs), "no empty image"
    assert any(i.encoding == "bogus_encoding" for i in imgs), "no unknown encoding"
    assert any(i.encoding == "" for i in imgs), "no empty encoding"
    assert any(i.height * i.step != len(i.data) and len(i.data) > 0 for i in imgs), "no size mismatch"
    assert any(len(i.data) >= fuzz.C.HUGE_BYTES for i in imgs) or any(
        i.height >= 2**31 for i in imgs), "no huge image"


def test_thermal_array_wrong_lengths():
    arrs = [decode(Float64MultiArray, c) for c in fuzz.generate_cases(Float64MultiArray) if c.typed]
    lengths = {len(a.data) for a in arrs}
    assert {0, 1, 1023, 1025} <= lengths
    assert any(len(a.data) == 1024 and all(math.isnan(v) for v in a.data) for a in arrs)


def test_laser_scan_length_mismatch_and_zero_increment():
    scans = [decode(LaserScan, c) for c in fuzz.generate_cases(LaserScan) if c.typed]
    assert any(len(s.ranges) == 719 for s in scans)
    assert any(s.angle_increment == 0.0 and len(s.ranges) == 720 for s in scans)
    assert any(len(s.ranges) == 0 for s in scans)


def test_strings_empty_huge_and_unknown_names():
    feeds = [decode(AgentDataFeed, c) for c in fuzz.generate_cases(AgentDataFeed, max_cases=80) if c.typed]
    ids = {f.agent_id for f in feeds}
    assert "" in ids
    assert "no_such_robot_4242" in ids
    assert any(len(i) >= fuzz.C.HUGE_STRING_LEN for i in ids)


def test_nested_arrays_are_populated_so_inner_fields_get_mutated():
    labels = [c.label for c in fuzz.generate_cases(ObjectDetectionList, max_cases=40)]
    assert any(lab.startswith("objects[0].") for lab in labels)
    assert "all variable arrays empty" in labels


def test_service_request_class():
    cases = fuzz.generate_cases(AskForRegionRequest, max_cases=30)
    reqs = [decode(AskForRegionRequest, c) for c in cases if c.typed]
    assert any(r.agent_id == "" for r in reqs) or any(r.label == "" for r in reqs)
    assert any(math.isnan(v) for r in reqs for v in _floats(r))


def test_max_cases_is_respected_and_raw_can_be_disabled():
    assert len(fuzz.generate_cases(Image, max_cases=5)) == 5
    assert all(c.typed for c in fuzz.generate_cases(Image, max_cases=20, include_raw=False))
    assert fuzz.generate_cases(Image, max_cases=0) == []


def test_stats_count_unserializable_candidates():
    stats = fuzz.GeneratorStats()
    fuzz.generate_cases(CameraInfo, max_cases=200, stats=stats)
    assert stats.candidates > 0
    assert stats.unserializable == len(stats.errors)


def test_path_helpers():
    msg = fuzz.populated(ObjectDetectionList)
    fuzz.set_path(msg, ("objects", 0, "pose", "pose", "position", "x"), 4.5)
    assert msg.objects[0].pose.pose.position.x == 4.5
    assert fuzz.path_str(("objects", 0, "pose")) == "objects[0].pose"
    assert fuzz.path_str(()) == "<msg>"
    with pytest.raises(ValueError):
        fuzz.message_class("no_pkg/NoMsg")


def test_single_field_nan_and_inf_within_a_small_budget():
    """A NaN in one field only (the rest valid) is sent even with the rostests' small case budgets."""
    cases = [c for c in fuzz.generate_cases(PoseStamped, max_cases=16) if c.label.startswith("only ")]
    assert len(cases) >= 2, [c.label for c in fuzz.generate_cases(PoseStamped, max_cases=16)]
    for c in cases:
        values = _floats(decode(PoseStamped, c))
        bad = [v for v in values if not math.isfinite(v)]
        assert len(bad) == 1, (c.label, values)
    assert any("NaN" in c.label for c in cases) and any("+inf" in c.label for c in cases)


def test_fuzz_report_fails_a_node_that_lost_its_function():
    from mbzirc_robustness.report import FuzzReport, merge_fuzz_reports
    rep = FuzzReport()
    rep.add_node("/est", 10)
    rep.add_function_check("/est", "/a", "/estimated_objects published", True, "ok")
    assert rep.to_dict()["summary"]["all_survived"]
    rep.add_function_check("/est", "/clock: one message 10 s in the past", "/estimated_objects published", False,
                           "/estimated_objects not published within 3.0 s")
    s = rep.to_dict()["summary"]
    assert not s["all_survived"] and s["functional_checks"] == 2, "alive (same pid) but silent is a failure"
    assert "clock" in s["function_lost"][0]["function_lost"]
    m = merge_fuzz_reports([rep.to_dict()])
    assert not m["summary"]["all_survived"] and m["summary"]["function_lost"]


# ---- crafted pickles for SMACH introspection servers --------------------------------------------------
def test_pickle_cases_reach_the_container_and_each_is_what_it_says(tmp_path):
    import base64
    import io
    import pickle

    from smach_msgs.msg import SmachContainerInitialStatusCmd
    marker = str(tmp_path / "ran")
    cases = fuzz.pickle_cases(SmachContainerInitialStatusCmd, "/SM_ROOT", marker)
    msgs = {c.label: decode(SmachContainerInitialStatusCmd, c) for c in cases}
    assert all(m.path == "/SM_ROOT" and m.initial_states == [] for m in msgs.values())
    by = {label.split(" (to ")[0]: m.local_data for label, m in msgs.items()}

    calls = []

    class Recording(pickle.Unpickler):
        """A trusting unpickler whose globals only record the call they would make."""
        def find_class(self, module, name):
            return lambda *args: calls.append((module, name, args))

    for label in ("pickle: calls os.system (would run code)", "pickle: calls builtins.exec (would run code)"):
        Recording(io.BytesIO(base64.b64decode(by[label]))).load()
    assert [(m, n) for m, n, _ in calls] == [("os", "system"), ("builtins", "exec")]
    assert all(marker in args[0] for _, _, args in calls)
    assert len(by[f"pickle: {fuzz.C.HUGE_PICKLE_CHARS} chars of base64"]) > fuzz.C.HUGE_PICKLE_CHARS * 0.99
    bomb = pickle.loads(base64.b64decode(by["pickle: reference bomb (2^60 values in a few hundred bytes)"]))
    assert len(by["pickle: reference bomb (2^60 values in a few hundred bytes)"]) < 2000 and bomb["fuzz"][0] is bomb["fuzz"][1]
    with pytest.raises(Exception):
        pickle.loads(base64.b64decode(by["pickle: valid pickle truncated by half"]))


def test_smach_ros_refuses_every_crafted_pickle_and_runs_no_code(tmp_path):
    """What the agents' introspection servers do with them (smach_ros's safe decoder)."""
    import os

    from smach_ros.userdata_codec import DecodeError, contains_opaque, decode_local_data
    marker = str(tmp_path / "ran")
    for label, text in fuzz.crafted_pickles(marker):
        try:
            data = decode_local_data(text)
        except DecodeError:
            continue
        assert contains_opaque(data), f"{label}: accepted as plain data"
    assert not os.path.exists(marker)
