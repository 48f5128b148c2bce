"""When hector_mapping matches (mapping_gate.py): paused on GNSS away from the buildings, resumed near one or
without a fix, with a hysteresis; and the anchor after a resume (anchor.IndoorPose.expect_new_map)."""
import math

import pytest

from indoor_localization.anchor import GNSS, IndoorPose
from indoor_localization.mapping_gate import MappingGate

TOWER = (11.4, 6.7, 24.2, 19.5, 18.0)      # x_min, y_min, x_max, y_max, top


def test_a_robot_at_home_pauses_and_resumes_only_once_near_a_building():
    gate = MappingGate((TOWER,), resume_within=8.0, pause_beyond=10.0)
    assert gate.update(True, 0.0, 0.0) is False             # at home, 13 m from the tower's south-west corner
    assert gate.update(True, 0.5, 12.0) is None               # 10.9 m from facade C: still paused
    assert gate.update(True, 3.5, 12.0) is True               # 7.9 m: a new map from here
    # flying along the limit does not reset the map over and over
    for x in (2.0, 3.5, 1.5, 3.0):                            # 8-10 m from facade C
        assert gate.update(True, x, 12.0) is None
    assert gate.update(True, 1.3, 12.0) is False              # 10.1 m


def test_inside_a_footprint_and_without_a_fix_it_always_matches():
    gate = MappingGate((TOWER,), 8.0, 10.0)
    gate.update(True, -20.0, 0.0)
    assert not gate.running
    assert gate.update(False, -20.0, 0.0) is True             # no fix: the SLAM pose is the only one there is
    assert gate.update(False, -30.0, 0.0) is None
    gate = MappingGate((TOWER,), 8.0, 10.0)
    assert gate.update(True, 15.0, 10.0) is None              # inside: distance 0


def test_bad_positions_keep_the_state_and_zero_never_pauses():
    gate = MappingGate((TOWER,), 8.0, 10.0)
    assert gate.update(True, math.nan, 0.0) is None and gate.running
    gate.update(True, -20.0, 0.0)
    assert gate.update(True, math.inf, math.nan) is None and not gate.running
    never = MappingGate((TOWER,), 8.0, 0.0)
    assert never.update(True, -100.0, 0.0) is None and never.running
    assert MappingGate((), 8.0, 10.0).update(True, 0.0, 0.0) is False   # no building: nothing to map
    with pytest.raises(ValueError):
        MappingGate((TOWER,), 12.0, 10.0)


def test_after_a_resume_the_new_maps_poses_are_anchored_afresh_not_taken_for_a_jump():
    """The resumed map's first pose is its origin wherever the robot is; the old map's anchor applied to it
    would put the robot at the old map's origin."""
    core = IndoorPose()
    for k in range(60):                                        # 2 s on the old map: anchored (identity)
        t = k / 30.0
        core.on_reported(t, 1.0 + 0.1 * t, 2.0, 5.0, 0.0)
        if k % 2 == 0:
            core.on_slam(t, 1.0 + 0.1 * t, 2.0, 0.0)
    assert core.anchor is not None
    frames = core.frame_changes
    core.expect_new_map()                                      # paused, flown 20 m, resumed
    assert core.anchor is None and core.frame_changes == frames + 1 and core.map_z == 5.0
    outputs = []
    for k in range(60):
        t = 30.0 + k / 30.0
        core.on_reported(t, 21.0 + 0.1 * k / 30.0, 2.0, 6.0, 0.0)
        if k % 2 == 0:
            outputs.append(core.on_slam(t, 0.1 * k / 30.0, 0.0, 0.0))
    events = core.pop_events()
    assert not any("jumped" in e for e in events), events
    o = outputs[-1]
    assert o is not None and o.source == GNSS and o.x == pytest.approx(21.0 + 0.1 * 58 / 30.0, abs=1e-6)
