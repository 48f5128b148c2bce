"""Indoor flights on SLAM: segmentation by the localization source, SLAM pose error against the truth, the
floor of a flight and of a robot's map, and summary.json without SLAM."""
import math

import pytest

from mbzirc_arena.c3 import ARENA
from mbzirc_referee.indoor_flights import (SlamRecord, anchor_from_pair, flight_summary, indoor_periods,
                                           interpolate_xy, joined, periods)
from mbzirc_referee.slam_maps import compose
from mbzirc_referee.summary import MissionRecord, check_summary

FLOOR_OF = ARENA.floor_of
Z1 = ARENA.floor_heights[1] + 1.2          # a height on the first floor


def test_periods_are_the_contiguous_runs_of_slam():
    changes = [(0.0, "gnss"), (10.0, "slam"), (25.0, "none"), (30.0, "slam"), (31.0, "slam"), (40.0, "gnss"),
               (50.0, "slam")]
    assert periods(changes, 70.0) == [(10.0, 25.0), (30.0, 40.0), (50.0, 70.0)]
    assert periods([(0.0, "gnss"), (5.0, "none")], 70.0) == []
    assert periods([], 70.0) == []


def test_interpolation_between_close_samples_only():
    s = [(1.0, 0.0, 0.0, 5.0), (1.1, 1.0, 2.0, 5.0), (2.0, 5.0, 5.0, 5.0)]
    assert interpolate_xy(s, 1.05) == pytest.approx((0.5, 1.0))
    assert interpolate_xy(s, 1.1) == (1.0, 2.0)
    assert interpolate_xy(s, 1.5) is None          # 0.9 s apart: a gap
    assert interpolate_xy(s, 0.5) is None and interpolate_xy(s, 2.5) is None
    assert interpolate_xy([], 1.0) is None


@pytest.mark.parametrize("anchor", [(0.0, 0.0, 0.0), (3.0, -2.0, 0.7), (-10.0, 5.5, -2.9)])
def test_the_anchor_of_a_pose_pair_maps_the_map_pose_onto_the_arena_pose(anchor):
    in_map = (1.5, -0.4, 0.3)
    in_arena = compose(anchor, in_map)
    got = anchor_from_pair(in_arena, in_map)
    assert got[:2] == pytest.approx(anchor[:2]) and math.isclose(math.cos(got[2] - anchor[2]), 1.0)


def _truth(t0, t1, z=Z1, dt=0.5):
    """A robot flying east at 1 m/s, true poses every dt."""
    n = int(round((t1 - t0) / dt))
    return [(t0 + k * dt, 10.0 + (t0 + k * dt), 5.0, z) for k in range(n + 1)]


def _slam(t0, t1, offset=(0.3, 0.4), z=Z1, dt=1 / 15):
    n = int((t1 - t0) / dt)
    return [(t0 + k * dt, 10.0 + t0 + k * dt + offset[0], 5.0 + offset[1], z) for k in range(n + 1)]


def test_flight_error_is_the_horizontal_distance_to_the_truth():
    f = flight_summary("2", (100.0, 110.0), _slam(100.0, 110.0), _truth(100.0, 110.0), FLOOR_OF)
    assert f["robot"] == "2" and f["floor"] == 1 and f["duration_s"] == 10.0
    assert f["samples"] == 21 and f["rms_error_m"] == pytest.approx(0.5) and f["max_error_m"] == pytest.approx(0.5)


def test_rms_and_max_see_an_outlier():
    slam = _slam(0.0, 10.0, offset=(0.0, 0.0))
    k = next(i for i, s in enumerate(slam) if abs(s[0] - 5.0) < 1e-9 or s[0] > 5.0)
    slam[k] = (slam[k][0], slam[k][1] + 2.0, slam[k][2], slam[k][3])
    truth = [s for s in _truth(0.0, 10.0) if s[0] != 5.0] + [(slam[k][0], 10.0 + slam[k][0], 5.0, Z1)]
    truth.sort()
    f = flight_summary("3", (0.0, 10.0), slam, truth, FLOOR_OF)
    assert f["max_error_m"] == pytest.approx(2.0, abs=1e-6)
    assert f["rms_error_m"] == pytest.approx(math.sqrt(4.0 / f["samples"]), abs=1e-3)


def test_the_error_on_slam_counts_only_while_the_robot_flew_on_it():
    """Explore + GNSS-denied mission, seeds 101-102: a UAV inside whose source went none (held, not flying on
    the SLAM pose) had a SLAM pose kilometres off (an unanchored map frame), and the flight's error read
    100 km. The error while on the slam source counts only those samples; without any, None."""
    slam = _slam(0.0, 10.0, offset=(0.0, 0.0))
    slam = [(t, x + (5000.0 if t > 5.0 else 0.0), y, z) for t, x, y, z in slam]      # lost after 5 s
    f = flight_summary("3", (0.0, 10.0), slam, _truth(0.0, 10.0), FLOOR_OF, on_slam_s=5.0,
                       slam_spans=[(0.0, 5.0)])
    assert f["max_error_m"] > 1000.0                                  # every sample: the unused pose too
    assert f["max_on_slam_m"] == pytest.approx(0.0, abs=1e-6) and f["rms_on_slam_m"] == pytest.approx(0.0, abs=1e-6)
    h = flight_summary("3", (0.0, 10.0), _slam(0.0, 10.0, offset=(0.0, 0.0)), _truth(0.0, 10.0), FLOOR_OF,
                       on_slam_s=5.0, slam_spans=[(2.0, 8.0)])
    assert h["first_on_slam_m"] == pytest.approx(0.0, abs=1e-6) and 2.0 <= h["t_max_on_slam"] <= 8.0
    g = flight_summary("3", (0.0, 10.0), slam, _truth(0.0, 10.0), FLOOR_OF)
    assert g["rms_on_slam_m"] is None and g["max_on_slam_m"] is None   # never on slam: only watched
    assert g["first_on_slam_m"] is None and g["t_max_on_slam"] is None


def test_samples_outside_the_flight_or_without_slam_poses_around_do_not_count():
    slam = [s for s in _slam(0.0, 20.0) if not 4.0 < s[0] < 6.0]           # SLAM silent 4-6 s
    f = flight_summary("2", (2.0, 12.0), slam, _truth(0.0, 30.0), FLOOR_OF)
    assert f["samples"] == 21 - 3                     # 2.0..12.0 every 0.5 s, minus 4.5, 5.0, 5.5
    empty = flight_summary("2", (2.0, 12.0), [], _truth(0.0, 30.0), FLOOR_OF)
    assert empty["samples"] == 0 and empty["rms_error_m"] is None and empty["max_error_m"] is None


def _source_at(t):
    """The schedule of robot 2's source: slam 100-130 s (floor 1), 200-205 s and 207-210 s (floor 2), lost
    between and after."""
    return "slam" if 100.0 <= t < 130.0 or 200.0 <= t < 205.0 or 207.0 <= t < 210.0 else \
        ("none" if t >= 200.0 else "gnss")


def _record_with_flights():
    rec = SlamRecord()
    rec.set_source("0", 0.0, "gnss")
    for t, x, y, z in _slam(90.0, 220.0):             # in time order, as the recorder hears them
        rec.set_source("2", t, _source_at(t))          # every pose: keep-alives are no change
        rec.add_pose("2", t, x, y, z if t < 150 else ARENA.floor_heights[2] + 1.0)
    for t, x, y, z in _truth(80.0, 220.0):
        rec.add_truth("2", t, x, y, z if t < 150 else ARENA.floor_heights[2] + 1.0)
        rec.add_truth("1", t, x, y, z)               # no SLAM: not kept
    return rec


def test_the_record_keeps_poses_and_truth_only_of_robots_that_run_slam():
    rec = _record_with_flights()
    rec.add_pose("1", 100.0, 1.0, 2.0, 3.0)          # no localization source: no SLAM
    assert "1" not in rec.truth and "1" not in rec.poses and len(rec.truth["2"]) == 281
    assert len(rec.poses["2"]) == len(_slam(90.0, 220.0))
    assert [c[1] for c in rec.sources["2"]] == ["gnss", "slam", "gnss", "slam", "none", "slam", "none"]
    assert rec.sources["2"][1][0] == pytest.approx(100.0, abs=0.07)
    assert rec.been_inside == {"2"}


BOX = (20.0, 0.0, 40.0, 10.0, 15.0)                  # a building: x 20-40, y 0-10, top 15 m


def test_indoors_is_inside_a_footprint_below_its_top():
    assert indoor_periods([], [BOX]) == []
    truth = [(t, 10.0 + t, 5.0, 16.0 if 24.0 <= t < 26.0 else 6.0) for t in range(0, 40)]   # x 10..49
    assert indoor_periods(truth, [BOX]) == [(10, 23), (26, 30)]                   # above the top at 24-25 s


def test_periods_closer_than_the_join_are_one():
    assert joined([(10.0, 20.0), (20.5, 30.0), (40.0, 41.0), (5.0, 12.0)], 1.0) == [(5.0, 30.0), (40.0, 41.0)]
    assert joined([]) == []


def test_a_robot_indoors_on_gnss_flies_indoors_too_and_its_slam_pose_is_scored():
    rec = SlamRecord(footprints=(BOX,))
    rec.set_source("3", 0.0, "gnss")                  # GNSS everywhere: the source never says slam
    for t, x, y, z in _slam(0.0, 40.0, offset=(0.0, 0.2)):
        rec.add_pose("3", t, x, y, z)
    for t, x, y, z in _truth(0.0, 40.0):               # x 10..50: inside from t = 10 to 30
        rec.add_truth("3", t, x, y, z)
    (f,) = rec.flights(40.0, FLOOR_OF)
    assert (f["t_start"], f["t_end"], f["on_slam_s"], f["floor"]) == (10.0, 30.0, 0.0, 1)
    assert f["samples"] == 41 and f["rms_error_m"] == pytest.approx(0.2) and rec.been_inside == {"3"}


def test_tracks_export_what_the_errors_came_from_for_robots_once_inside_only():
    rec = SlamRecord(footprints=(BOX,))
    rec.set_source("3", 0.0, "gnss")
    rec.set_source("1", 0.0, "gnss")                   # never inside: nothing to look at
    for t, x, y, z in _slam(0.0, 40.0, offset=(0.0, 0.2)):
        rec.add_pose("3", t, x, y, z)
        rec.add_pose("1", t, x, y + 50.0, z)
    for t, x, y, z in _truth(0.0, 40.0):
        rec.add_truth("3", t, x, y, z)
    tracks = rec.tracks()
    assert list(tracks) == ["3"] and tracks["3"]["sources"] == [[0.0, "gnss"]]
    assert len(tracks["3"]["poses"]) == len(rec.poses["3"]) and len(tracks["3"]["truth"]) == len(rec.truth["3"])
    t, x, y, _ = tracks["3"]["poses"][0]
    assert (t, x, y) == pytest.approx(rec.poses["3"][0][:3], abs=1e-3)


def test_slam_and_indoor_periods_of_one_entry_are_one_flight():
    rec = SlamRecord(footprints=(BOX,))
    rec.set_source("2", 0.0, "gnss")
    rec.set_source("2", 10.2, "slam")                 # the source follows the truth by a fraction of a second
    rec.set_source("2", 30.3, "gnss")
    for t, x, y, z in _truth(0.0, 40.0):
        rec.add_truth("2", t, x, y, z)
    (f,) = rec.flights(40.0, FLOOR_OF)
    assert (f["t_start"], f["t_end"], f["on_slam_s"]) == (10.0, 30.3, 20.1)


def test_flights_and_the_floor_of_a_map():
    rec = _record_with_flights()
    flights = rec.flights(300.0, FLOOR_OF)
    assert [(f["robot"], f["floor"], round(f["t_start"])) for f in flights] == [("2", 1, 100), ("2", 2, 200),
                                                                               ("2", 2, 207)]
    assert flights[0]["duration_s"] == pytest.approx(30.0, abs=0.1) and flights[0]["rms_error_m"] == 0.5
    assert rec.map_floors(300.0, FLOOR_OF) == {"2": 1}    # 30 s on floor 1 in one flight, 8 s on floor 2 in two


def test_summary_without_slam_has_an_empty_list_and_is_complete():
    r = MissionRecord(seed=1, duration=100.0)
    r.set_score(50.0, 0.0, [])
    s = r.summary(10.0, "time")
    assert s["indoor_flights"] == [] and check_summary(s) == []


def test_summary_lists_the_flights():
    r = MissionRecord(seed=1, duration=400.0)
    r.slam = _record_with_flights()
    r.set_score(300.0, 0.0, [])
    s = r.summary(10.0, "time")
    assert [f["floor"] for f in s["indoor_flights"]] == [1, 2, 2]
    assert {"robot", "floor", "duration_s", "samples", "rms_error_m", "max_error_m"} <= set(s["indoor_flights"][0])
