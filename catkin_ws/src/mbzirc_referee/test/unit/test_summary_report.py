"""The referee's record, summary.json completeness and report.png."""
import json
import math
import os

from mbzirc_referee.report import write_report
from mbzirc_referee.summary import MissionRecord, check_summary


def _record():
    r = MissionRecord(seed=7, duration=100.0)
    r.robot_kinds.update({"1": "blanket", "2": "water", "0": "ugv"})
    for t in range(0, 60, 1):
        r.add_pose("1", float(t), -2 + t * 0.1, 1.65, 3.0)
        r.add_pose("2", float(t), 0.0, t * 0.3, 5.5)
        r.add_pose("0", float(t), 4.0 + t * 0.2, -4.0, 0.0)
    r.update_fire("ground_0", 1, 0, (1.0, 1.65, 0.0), True, False, 0.0, -1)
    r.update_fire("facade_C_3", 0, 2, (11.4, 14.5, 10.5), True, False, 0.4, -1)
    r.update_fire("facade_C_4", 0, 2, (11.4, 8.5, 12.5), False, False, 0.0, -1)  # inactive holder
    return r


def test_inactive_holders_are_not_fires():
    r = _record()
    assert set(r.fires) == {"ground_0", "facade_C_3"}


def test_extinguish_is_credited_to_the_nearest_robot_of_the_right_kind():
    r = _record()
    r.set_score(30.0, 0.4, [])
    r.update_fire("ground_0", 1, 0, (4.0, 1.65, 0.0), True, True, 1.0, 31.0)
    r.update_fire("facade_C_3", 0, 2, (11.4, 14.5, 10.5), True, True, 1.0, 55.0)
    s = r.summary(20.0, "all_fires_out")
    by = {f["id"]: f["extinguished_by"] for f in s["fires"]}
    assert by == {"ground_0": "1", "facade_C_3": "2"}  # the UGV is nearer the ground fire but has no blanket
    assert s["fires_extinguished"] == 2 and s["fires_total"] == 2
    assert s["all_out_time_s"] == 55.0
    assert check_summary(s) == []


def test_end_conditions():
    r = _record()
    assert r.finished(2) is None
    r.set_score(100.0, 0.0, ["mbzirc2020_2"])
    assert r.finished(2) == "time"
    r2 = _record()
    r2.update_fire("ground_0", 1, 0, (1.0, 1.65, 0.0), True, True, 1.0, 10.0)
    assert r2.finished(2) is None
    r2.update_fire("facade_C_3", 0, 2, (11.4, 14.5, 10.5), True, True, 1.0, 12.0)
    assert r2.finished(2) == "all_fires_out"
    assert r2.finished(8) is None  # fewer fires known than expected: not over yet


def test_summary_fields_and_rtf_and_min_separation():
    r = _record()
    r.set_score(60.0, 0.5, ["mbzirc2020_3"])
    s = r.summary(15.0, "time", {"uavs": 3})
    assert s["real_time_factor"] == 4.0 and s["sim_time_s"] == 60.0 and s["crashes"] == ["mbzirc2020_3"]
    assert s["uavs"] == 3
    assert math.isclose(s["min_separation_m"], min(
        math.dist((-2 + t * 0.1, 1.65, 3.0), (0.0, t * 0.3, 5.5)) for t in range(60)), rel_tol=0.2)
    assert check_summary({"seed": 1}) != []
    assert "fires[0].kind=lava" in check_summary({**s, "fires": [{**s["fires"][0], "kind": "lava"}]})


def test_report_png_is_written(tmp_path):
    r = _record()
    r.set_score(60.0, 1.0, [])
    path = os.path.join(tmp_path, "report.png")
    write_report(r, path)
    with open(path, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert os.path.getsize(path) > 10000
    json.dumps(r.summary(1.0))


def test_a_feed_without_a_pose_is_no_place():
    """An agent's feed before its UAL's first pose carries an empty PoseStamped: (0, 0, 0) is not where the
    robot is (it once made a 0.56 m "closest approach" of the UGV and a UAV taking off)."""
    from mbzirc_comm_objs.msg import AgentDataFeed
    from mbzirc_arena.messages import feed_position
    f = AgentDataFeed()
    assert feed_position(f) is None
    f.pose.header.frame_id = "arena"
    f.pose.pose.position.x, f.pose.pose.position.y, f.pose.pose.position.z = 4.0, -4.0, 0.2
    assert feed_position(f) == (4.0, -4.0, 0.2)
    f.pose.pose.position.y = math.nan
    assert feed_position(f) is None


def test_separation_is_judged_on_the_true_poses_when_the_simulator_gives_them():
    """Realistic seed 108: UAVs 1 and 3 taking off from pads 2.6 m apart, each data_feed off by its GNSS bias
    (0.6-0.8 m towards the other), were reported 1.28 m apart; the referee's verdict is the truth's."""
    r = MissionRecord(seed=108, duration=100.0)
    for k in range(6):
        t, z = 2.0 + 0.5 * k, 0.2 * k
        r.add_pose("1", t, -1.76, 2.39, 0.5 + z)        # GNSS: pad (-2.0, 1.65) + bias
        r.add_pose("3", t, -0.64, 2.77, 0.4 + z)        # GNSS: pad (0.0, 3.3) + bias
        r.add_true_pose("1", t, -2.0, 1.65, z)
        r.add_true_pose("3", t, 0.0, 3.3, z)
    s = r.summary(10.0)
    assert s["separation_source"] == "truth"
    assert math.isclose(s["min_separation_m"], math.hypot(2.0, 1.65), abs_tol=1e-3)
    assert s["closest_approach"]["robots"] == ["1", "3"]
    assert s["min_reported_separation_m"] < 1.3
    # two robots on the ground are no approach
    assert s["closest_approach"]["t"] >= 3.0


def test_separation_falls_back_to_the_data_feeds_without_truth():
    s = _record().summary(10.0)
    assert s["separation_source"] == "data_feed" and "min_reported_separation_m" not in s


def test_summary_says_where_the_water_went_per_fire_and_per_robot():
    """summary.json tells how many litres each fire received and each robot pumped, put into fires, lost on
    walls or short, per fire kind: so a fire left at 0.96 after three tanks tells a bad aim (water beside
    the hole) from an early 'out' judgment (little water pumped at it)."""
    from mbzirc_referee.summary import Pour
    r = _record()
    r.update_fire("indoor_in1_w", 2, 1, (17.7, 8.5, 4.5), True, False, 0.5, -1, 0.6, 1.2)
    r.update_fire("facade_C_3", 0, 2, (11.4, 14.5, 10.5), True, False, 0.4, -1, 0.4, 1.0)
    r.set_water("2", [Pour("indoor_in1_w", "indoor", 3.0, 0.6, 2.4, 0.0), Pour("facade_C_3", "facade", 0.6, 0.4, 0.1, 0.1),
                      Pour(None, None, 0.4, 0.0, 0.0, 0.4)])
    s = r.summary(20.0, "time")
    assert check_summary(s) == []
    fires = {f["id"]: f for f in s["fires"]}
    assert fires["indoor_in1_w"]["litres_received"] == 0.6 and fires["indoor_in1_w"]["litres_needed"] == 1.2
    assert fires["indoor_in1_w"]["litres_aimed"] == 3.0
    assert fires["indoor_in1_w"]["litres_by_robot"] == {"2": 0.6}
    assert fires["ground_0"]["litres_received"] is None                     # a blanket's fire
    robot = s["robots"]["2"]
    assert (robot["litres_pumped"], robot["litres_into_fires"], robot["efficiency"]) == (4.0, 1.0, 0.25)
    assert robot["litres_on_walls"] == 2.5 and robot["litres_fell_short"] == 0.5
    assert robot["pours"][0] == {"fire": "indoor_in1_w", "kind": "indoor", "litres_aimed": 3.0, "litres_in": 0.6,
                                 "litres_on_wall": 2.4, "litres_fell_short": 0.0}
    assert s["water_efficiency"] == {"facade": {"litres_pumped": 0.6, "litres_into_fires": 0.4, "efficiency": 0.667},
                                     "indoor": {"litres_pumped": 3.0, "litres_into_fires": 0.6, "efficiency": 0.2}}
    assert "robots" in check_summary({k: v for k, v in s.items() if k != "robots"})
    json.dumps(s)


def test_the_recorder_keeps_the_simulators_water_account():
    """/sim/water (ual_sim/WaterAccount) as the record keeps it, after a trip on the wire."""
    import io
    import threading
    from ual_sim.msg import WaterAccount, WaterUse
    from mbzirc_referee import recorder as R
    rec = R.MissionRecorder.__new__(R.MissionRecorder)
    rec.rec, rec.lock = MissionRecord(), threading.Lock()
    msg = WaterAccount(robots=[WaterUse(robot_id=3, litres_pumped=2.0, litres_into_fires=0.5, litres_on_walls=1.5,
                                        holder_ids=["", "in2_e"], holder_kinds=[WaterUse.NO_HOLDER, 2],
                                        aimed=[0.25, 1.75], entered=[0.0, 0.5], on_wall=[0.25, 1.25],
                                        fell_short=[0.0, 0.0])])
    buf = io.BytesIO()
    msg.serialize(buf)
    rec._on_water(WaterAccount().deserialize(buf.getvalue()))
    assert [(p.fire, p.kind, p.aimed, p.entered, p.on_wall) for p in rec.rec.water["3"]] == [
        (None, None, 0.25, 0.0, 0.25), ("in2_e", "indoor", 1.75, 0.5, 1.25)]
    assert rec.rec.summary(1.0)["robots"]["3"]["efficiency"] == 0.25
