"""The recorder's SLAM side without a ROS master (rospy's clock, params and log replaced): malformed maps are
refused with a throttled warning and the recorder goes on, each floor's map file is written from the robots'
grids and anchors, report.png draws the floor maps."""
import math
import threading
from types import SimpleNamespace

import numpy as np
import pytest

from mbzirc_arena.c3 import ARENA
from mbzirc_referee import slam_inputs as S
from mbzirc_referee.indoor_flights import SlamRecord
from mbzirc_referee.report import write_report
from mbzirc_referee.slam_maps import OCCUPIED, read_map_server
from mbzirc_referee.summary import MissionRecord

Z = {1: ARENA.floor_heights[1] + 1.0, 2: ARENA.floor_heights[2] + 1.0}


@pytest.fixture
def inputs(monkeypatch):
    warnings = []
    monkeypatch.setattr(S.rospy, "get_time", lambda: 100.0)
    monkeypatch.setattr(S.rospy, "get_param", lambda name, default=None: [0, 1, 2, 3])
    monkeypatch.setattr(S.rospy, "logwarn_throttle", lambda _period, text: warnings.append(text))
    monkeypatch.setattr(S.rospy, "logwarn", warnings.append)
    si = S.SlamInputs.__new__(S.SlamInputs)                 # its callbacks without its ROS set-up
    si.slam, si.lock, si.arena_frame = SlamRecord(), threading.Lock(), "arena"
    si.grids, si.recent, si.truth_ids, si.anchor_t = {}, {}, None, {}
    si.period_grids, si.fetch_lock = {}, threading.Lock()
    si.warnings = warnings
    return si


def grid_msg(width=40, height=40, res=0.1, data=None, frame="mbzirc2020_2/map", origin=(-2.0, -2.0)):
    cells = np.zeros((height, width), dtype=np.int8) if data is None else data
    if data is None:
        cells[30, :] = 100                                  # a wall at map y = 1.05
    info = SimpleNamespace(width=width, height=height, resolution=res,
                           origin=SimpleNamespace(position=SimpleNamespace(x=origin[0], y=origin[1], z=0.0),
                                                  orientation=SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0)))
    return SimpleNamespace(info=info, data=cells.reshape(-1) if data is None else data,
                           header=SimpleNamespace(frame_id=frame))


def pose_msg(t, x, y, z, yaw=0.0):
    return SimpleNamespace(header=SimpleNamespace(stamp=SimpleNamespace(to_sec=lambda: t)),
                           pose=SimpleNamespace(position=SimpleNamespace(x=x, y=y, z=z),
                                                orientation=SimpleNamespace(x=0.0, y=0.0, z=math.sin(yaw / 2),
                                                                            w=math.cos(yaw / 2))))


@pytest.mark.parametrize("msg", [grid_msg(data=[0] * 7), grid_msg(res=math.nan), grid_msg(width=0, data=[])])
def test_a_malformed_map_is_refused_with_a_warning_and_the_last_good_one_kept(inputs, msg):
    assert inputs.accept_map("2", grid_msg())
    assert not inputs.accept_map("2", msg)
    assert inputs.warnings and "malformed map of robot 2 refused" in inputs.warnings[-1]
    assert inputs.grids["2"][0].cells.shape == (40, 40)


def test_non_finite_poses_and_a_truth_of_the_wrong_size_are_ignored(inputs):
    inputs._on_source(SimpleNamespace(data="slam"), "2")
    inputs._on_pose(pose_msg(1.0, math.nan, 0.0, 5.0), "2")
    inputs._on_slam_pose(pose_msg(1.0, 0.0, math.inf, 0.0), "2")
    assert len(inputs.warnings) == 2 and not inputs.slam.poses.get("2") and not inputs.recent.get(("2", "map"))
    inputs._on_truth(SimpleNamespace(header=SimpleNamespace(stamp=SimpleNamespace(to_sec=lambda: 1.0)),
                                     poses=[pose_msg(0, 1, 2, 3).pose] * 3))        # 4 robot ids
    assert "/sim/robots has 3 poses" in inputs.warnings[-1] and not inputs.slam.truth


def fly(inputs, robot, floor, anchor, t0=10.0):
    """Robot on SLAM for 10 s on `floor`: its SLAM poses paired with the anchored ones, truth at 2 Hz."""
    c, s = math.cos(anchor[2]), math.sin(anchor[2])
    inputs._on_source(SimpleNamespace(data="gnss"), robot)
    inputs.slam.set_source(robot, t0, "slam")
    for k in range(150):
        t, mx, my = t0 + k / 15, 0.1 * k / 15, 0.0
        ax, ay = anchor[0] + c * mx - s * my, anchor[1] + s * mx + c * my
        calls = [lambda: inputs._on_slam_pose(pose_msg(t, mx, my, 0.0), robot),
                 lambda: inputs._on_pose(pose_msg(t, ax, ay, Z[floor], anchor[2]), robot)]
        for call in calls if k % 2 else calls[::-1]:    # the two topics come in either order
            call()
        if k % 7 == 0:
            inputs.slam.add_truth(robot, t, ax + 0.05, ay, Z[floor])


def test_the_anchor_is_the_newest_pair_whichever_topic_comes_first(inputs):
    inputs._on_source(SimpleNamespace(data="gnss"), "2")
    inputs._on_pose(pose_msg(2.0, 11.0, 5.0, 6.0, math.pi / 2), "2")          # anchored pose first
    inputs._on_slam_pose(pose_msg(1.0, 0.0, 0.0, 0.0), "2")                   # an unpaired SLAM pose
    assert "2" not in inputs.slam.anchors
    inputs._on_slam_pose(pose_msg(2.0, 1.0, 0.0, 0.0), "2")                   # its SLAM pose after it
    assert inputs.slam.anchors["2"] == pytest.approx((11.0, 4.0, math.pi / 2))
    inputs._on_pose(pose_msg(1.0, 0.0, 0.0, 6.0, 0.0), "2")                   # a late pair: older, ignored
    assert inputs.slam.anchors["2"] == pytest.approx((11.0, 4.0, math.pi / 2)) and inputs.anchor_t["2"] == 2.0


def test_each_floor_map_is_written_where_the_anchor_puts_it(inputs, tmp_path):
    fly(inputs, "2", 1, (20.0, 10.0, math.pi / 2))
    fly(inputs, "0", 2, (5.0, 5.0, 0.0))
    assert inputs.slam.anchors["2"] == pytest.approx((20.0, 10.0, math.pi / 2))
    inputs.accept_map("2", grid_msg())
    inputs.accept_map("0", grid_msg())
    entries, maps = inputs.write_maps(str(tmp_path), 30.0, ARENA.floor_of)
    assert [(e["floor"], e["robots"]) for e in entries] == [(1, ["2"]), (2, ["0"])]
    assert entries[0]["anchors"]["2"]["pose"] == pytest.approx([20.0, 10.0, math.pi / 2], abs=1e-3)
    m1 = read_map_server(str(tmp_path / "map_floor1.yaml"))
    # robot 2's wall at map y = 1.05 turned by 90 deg about (20, 10): arena x = 18.95, y from 8 to 12
    col = int((18.95 - m1.origin[0]) / m1.resolution)
    rows = [int((y - m1.origin[1]) / m1.resolution) for y in (8.2, 10.0, 11.8)]
    assert all(m1.codes[r, col] == OCCUPIED for r in rows)
    assert np.array_equal(m1.codes, maps[1].codes)
    m2 = read_map_server(str(tmp_path / "map_floor2.yaml"))
    assert m2.origin == pytest.approx((3.0, 3.0))       # robot 0's grid corner (-2, -2) + its anchor (5, 5)


def test_a_robot_whose_map_never_came_is_said_and_skipped(inputs, tmp_path):
    fly(inputs, "3", 1, (0.0, 0.0, 0.0))
    entries, maps = inputs.write_maps(str(tmp_path), 30.0, ARENA.floor_of)
    assert entries == [] and maps == {} and "its map never came" in inputs.warnings[-1]
    assert not list(tmp_path.iterdir())


def test_report_draws_the_floor_maps(inputs, tmp_path):
    fly(inputs, "2", 1, (20.0, 10.0, 0.3))
    inputs.accept_map("2", grid_msg())
    _, maps = inputs.write_maps(str(tmp_path), 30.0, ARENA.floor_of)
    rec = MissionRecord(seed=3, duration=60.0)
    rec.slam = inputs.slam
    rec.set_score(30.0, 0.0, [])
    write_report(rec, str(tmp_path / "with_maps.png"), floor_maps=maps)
    write_report(rec, str(tmp_path / "without.png"))
    import matplotlib.image as mpimg
    assert mpimg.imread(str(tmp_path / "with_maps.png")).shape[0] > 1.5 * mpimg.imread(
        str(tmp_path / "without.png")).shape[0]                 # a row of floor panels below


def test_a_floor_map_is_the_one_of_its_slam_period_not_the_newest_map_of_its_robot(inputs, tmp_path, monkeypatch):
    """indoor_pose starts a new SLAM map outside for every height band: a UAV's newest map at the end of the
    trial is its transit altitude's, in another frame. The map fetched as it leaves SLAM (its source turns
    from slam to gnss) is its floor's, placed with the anchor of that moment."""
    fetched = []

    def fetch(robot, period=None):                   # the service's answer: the floor's grid
        fetched.append((robot, period))
        inputs.accept_map(robot, grid_msg(), period)
    monkeypatch.setattr(inputs, "_fetch", fetch)
    started = []
    monkeypatch.setattr(S.threading, "Thread", lambda target, args, **kw: SimpleNamespace(
        start=lambda: started.append(target(*args))))
    fly(inputs, "2", 1, (20.0, 10.0, math.pi / 2))
    inputs._on_source(SimpleNamespace(data="gnss"), "2")            # out through the window
    assert fetched == [("2", 10.0)] and ("2", 10.0) in inputs.period_grids
    # outside, a new map in a new frame (its anchor moved), fetched on GNSS: not the floor's
    inputs.slam.anchors["2"] = (-30.0, 40.0, 0.0)
    inputs.accept_map("2", grid_msg(origin=(-8.0, -8.0)))
    entries, _ = inputs.write_maps(str(tmp_path), 130.0, ARENA.floor_of)
    assert [(e["floor"], e["robots"]) for e in entries] == [(1, ["2"])]
    assert entries[0]["anchors"]["2"]["pose"] == pytest.approx([20.0, 10.0, math.pi / 2], abs=1e-3)
    m1 = read_map_server(str(tmp_path / "map_floor1.yaml"))
    col = int((18.95 - m1.origin[0]) / m1.resolution)           # the wall where the floor's anchor puts it
    assert all(m1.codes[int((y - m1.origin[1]) / m1.resolution), col] == OCCUPIED for y in (8.2, 10.0, 11.8))
