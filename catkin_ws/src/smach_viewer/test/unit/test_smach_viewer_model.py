"""ViewerModel and build_dot: structure/status bookkeeping, safe userdata, DOT ids, bad input."""
import base64
import os
import pickle

import pytest

from smach_ros.userdata_codec import encode_local_data
from smach_viewer.model import ViewerModel, build_dot


def feed(m, server="/srv"):
    m.update_structure(server, "/ROOT", ["A", "SUB", "CC"], ["go", "fin", "seen", "stop"],
                       ["A", "SUB", "CC", "A"], ["SUB", "CC", "done", "None"], ["done", "stop"])
    m.update_structure(server, "/ROOT/SUB", ["X", "Y"], ["next", "fin"], ["X", "Y"], ["Y", "None"], ["fin"])
    m.update_structure(server, "/ROOT/CC", ["P", "Q"], ["ok"], ["P"], ["seen"], ["seen"])


def test_structure_versions_only_bump_on_change():
    m = ViewerModel()
    feed(m)
    v = m.snapshot()["servers"]["/srv"]["structure_version"]
    feed(m)  # heartbeat repeats: no relayout
    assert m.snapshot()["servers"]["/srv"]["structure_version"] == v
    m.update_structure("/srv", "/ROOT/SUB", ["X"], [], [], [], ["fin"])
    assert m.snapshot()["servers"]["/srv"]["structure_version"] > v


def test_status_decodes_userdata_safely():
    class Evil:
        def __reduce__(self):
            return (os.system, ("touch /tmp/smach_viewer_pwned",))

    m = ViewerModel()
    feed(m)
    m.update_status("/srv", "/ROOT", ["A"], ["SUB"], encode_local_data({"n": 1, "l": [1, 2]}), "TRANSITION")
    c = m.snapshot()["servers"]["/srv"]["containers"]["/ROOT"]
    assert c["active_states"] == ["SUB"] and c["userdata"] == {"n": 1, "l": [1, 2]} and c["info"] == "TRANSITION"
    if os.path.exists("/tmp/smach_viewer_pwned"):
        os.remove("/tmp/smach_viewer_pwned")
    m.update_status("/srv", "/ROOT", [], [], base64.b64encode(pickle.dumps({"e": Evil()}, 2)).decode(), "")
    assert not os.path.exists("/tmp/smach_viewer_pwned")
    assert m.snapshot()["servers"]["/srv"]["containers"]["/ROOT"]["userdata"]["e"]["__class__"].endswith("system")
    m.update_status("/srv", "/ROOT", [], [], "garbage!!", "")
    c = m.snapshot()["servers"]["/srv"]["containers"]["/ROOT"]
    assert c["userdata"] is None and c["userdata_error"]


def test_bad_messages_rejected():
    m = ViewerModel()
    with pytest.raises(ValueError):
        m.update_structure("/srv", "/ROOT", ["A"], ["x", "y"], ["A"], ["B"], [])
    with pytest.raises(ValueError):
        m.update_structure("/srv", "ROOT", [], [], [], [], [])
    with pytest.raises(ValueError):
        m.update_status("/srv", "nopath", [], [], "", "")


def test_wait_for_change_and_remove_server():
    m = ViewerModel()
    v = m.version
    assert m.wait_for_change(v, 0.01) == v
    feed(m)
    assert m.wait_for_change(v, 0.01) != v
    m.remove_server("/srv")
    assert m.servers() == []
    assert m.dot("/srv") is None


def test_stale_flag_after_silence():
    now = [0.0]
    m = ViewerModel(clock=lambda: now[0])
    feed(m)
    assert not m.snapshot()["servers"]["/srv"]["stale"]
    now[0] = 100.0
    assert m.snapshot()["servers"]["/srv"]["stale"]


def test_dot_has_ids_clusters_and_edges():
    m = ViewerModel()
    feed(m)
    m.update_status("/srv", "/ROOT/SUB", ["X"], [], "", "")
    dot = m.dot("/srv")
    assert 'subgraph "cluster_/ROOT"' in dot and 'subgraph "cluster_/ROOT/SUB"' in dot
    assert 'id="s:/ROOT/A"' in dot and 'id="s:/ROOT/SUB/X"' in dot and 'id="o:/ROOT:done"' in dot
    assert 'id="c:/ROOT/CC"' in dot
    # edge into a nested machine points at its initial state, clipped at the cluster
    assert '"/ROOT/A" -> "/ROOT/SUB/X" [label="go", lhead="cluster_/ROOT/SUB"]' in dot
    # out of a nested machine from its outcome box
    assert '"/ROOT/SUB:fin" -> "/ROOT/CC/P"' in dot
    # 'None' target falls through to the container outcome of the same name
    assert '"/ROOT/A" -> "/ROOT:stop" [label="stop"]' in dot
    assert '"/ROOT/SUB/Y" -> "/ROOT/SUB:fin"' in dot


def test_dot_escapes_hostile_labels():
    dot = build_dot("/s", {})
    assert dot.startswith("digraph")
    m = ViewerModel()
    m.update_structure("/s", "/R", ['a"b\\c', "<x>"], [], [], [], ['o"'])
    dot = m.dot("/s")
    assert '"/R/a\\"b\\\\c"' in dot


def test_debug_status_is_validated_and_bounded():
    import json
    import pytest
    from smach_viewer.model import MAX_DEBUG_STATUS_CHARS, ViewerModel
    m = ViewerModel()
    m.update_structure("/s", "/R", ["A"], [], [], [], ["x"])
    good = {"allowed": True, "breakpoints": ["/R/A"], "paused": [{"path": "/R/A", "outcomes": ["x"],
                                                                   "userdata": {}, "userdata_notes": []}]}
    m.update_debug("/s", json.dumps(good))
    assert m.snapshot()["servers"]["/s"]["debug"] == good
    for bad in ("[]", '{"allowed": "yes"}', '{"allowed": true, "paused": [{"path": 1}]}', "not json",
                json.dumps({"allowed": True, "pad": "x" * MAX_DEBUG_STATUS_CHARS})):
        with pytest.raises(ValueError):
            m.update_debug("/s", bad)
    assert m.debug("/s") == good
    m.remove_server("/s")
    assert m.debug("/s") is None
