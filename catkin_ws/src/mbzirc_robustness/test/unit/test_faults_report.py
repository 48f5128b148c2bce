"""Tests of the fault verdicts and the reports (pure)."""
import json

from mbzirc_robustness import faults as F
from mbzirc_robustness.report import FuzzReport, format_robustness, robustness_report, write_json


def status(t, alive, owners, tasks=None, indoor=None):
    agents = {r: {"alive": a, "task": (tasks or {}).get(r, "")} for r, a in alive.items()}
    return (t, {"t": t, "agents": agents, "floor_owner": owners, "indoor_owner": indoor or {}})


def test_default_schedule_has_every_fault_kind_once():
    sched = F.default_schedule(uavs=3)
    kinds = [f.kind for f in sched]
    assert kinds.count(F.KIND_CRASH) == 7
    assert kinds.count(F.KIND_LINK_CUT) == 1 and kinds.count(F.KIND_LINK_CUT_PERMANENT) == 1
    for k in (F.KIND_CLOCK_JUMP, F.KIND_SIM_RESTART, F.KIND_FLOOD, F.KIND_TASK_EXCEPTION):
        assert kinds.count(k) == 1, k
    cut = next(f for f in sched if f.kind == F.KIND_LINK_CUT)
    assert cut.target == "2" and cut.duration_s == 60.0
    assert next(f for f in sched if f.kind == F.KIND_LINK_CUT_PERMANENT).target == "3"
    crashes = {f.target: f.check for f in sched if f.kind == F.KIND_CRASH}
    assert crashes == {"/mbzirc2020_2/fire_detector": F.CHECK_DETECTIONS, "/mbzirc2020_1/agent": F.CHECK_DATA_FEED,
                       "/object_estimator": F.CHECK_TRACKS, "/region_manager": F.CHECK_REGIONS,
                       "/mbzirc2020_2/circle_detector": F.CHECK_INPUTS, "/mbzirc2020_0/agent": F.CHECK_DATA_FEED,
                       "/central_unit": F.CHECK_DECISIONS}
    assert sched[-1].target == "/central_unit", "the central unit goes last"
    assert [f.at_s for f in sched] == sorted(f.at_s for f in sched)
    assert not any(f.kind == F.KIND_LINK_CUT_PERMANENT for f in F.default_schedule(uavs=2))
    assert "/mbzirc2020_0/agent" not in {f.target for f in F.default_schedule(uavs=3, ugv=False)}


def test_temporary_cut_survived_with_reassignment_and_return():
    h = [status(10, {"2": True, "3": True}, {"2": "2", "3": "3"}),
         status(20, {"2": True, "3": True}, {"2": "2", "3": "3"}),
         status(26, {"2": False, "3": True}, {"3": "3"}),
         status(30, {"2": False, "3": True}, {"2": "3"})] + \
        [status(t, {"2": False, "3": True}, {"2": "3"}) for t in range(40, 81, 10)] + \
        [status(85, {"2": True, "3": True}, {"2": "3"}, tasks={"2": "search_facade"})]
    r = F.evaluate_link_cut(h, "2", t_cut=21, t_restore=81)
    assert r["survived"], r
    assert r["t_noticed"] == 26 and r["floors_owned_at_cut"] == ["f2"] and r["floors_reassigned"] == ["f2"]
    assert r["t_back"] == 85 and r["got_work_again"]
    assert r["owner_timeline"] == {"f2": [[20, "2"], [26, None], [30, "3"]]}


def test_cut_fails_when_never_noticed_or_floor_stuck_or_never_back():
    h = [status(10, {"2": True}, {"2": "2"}), status(30, {"2": True}, {"2": "2"}),
         status(40, {"2": True}, {"2": "2"})]
    r = F.evaluate_link_cut(h, "2", t_cut=20, t_restore=35)
    assert not r["survived"] and "never marked" in r["detail"]
    h2 = [status(10, {"2": True, "3": True}, {"2": "2"}), status(25, {"2": False, "3": True}, {"2": "2"}),
          status(90, {"2": False, "3": True}, {"2": "2"})]
    r2 = F.evaluate_link_cut(h2, "2", t_cut=20, t_restore=80)
    assert not r2["survived"]
    assert "still owned" in r2["detail"] and "['3'] were free" in r2["detail"] and "never came back" in r2["detail"]
    busy = [status(t, a, o, tasks={"3": "search_facade"}) for t, a, o in
            [(10, {"2": True, "3": True}, {"2": "2"})] + [(t, {"2": False, "3": True}, {"2": "2"})
                                                          for t in range(25, 86, 10)]
            + [(90, {"2": True, "3": True}, {"2": "2"})]]
    r3 = F.evaluate_link_cut(busy, "2", t_cut=20, t_restore=80)
    assert r3["survived"], r3
    assert r3["floors_kept_no_free_robot"] == ["f2"]


def test_permanent_cut_and_status_gap():
    h = [status(10, {"3": True}, {"3": "3"}), status(25, {"3": False}, {"3": "1"}),
         status(80, {"3": False}, {"3": "1"})]
    r = F.evaluate_link_cut(h, "3", t_cut=20, t_restore=None)
    assert not r["survived"] and "stopped" in r["detail"], "a 55 s gap in status is a stalled central unit"
    h.insert(2, status(40, {"3": False}, {"3": "1"}))
    h.insert(3, status(55, {"3": False}, {"3": "1"}))
    h.insert(4, status(68, {"3": False}, {"3": "1"}))
    r = F.evaluate_link_cut(h, "3", t_cut=20, t_restore=None)
    assert r["survived"], r
    assert F.robots_lost(h) == ["3"]


def test_fuzz_report_marks_deaths_restarts_and_silence():
    rep = FuzzReport()
    rep.add_node("/a", 10)
    rep.add_node("/b", 11)
    rep.add_node("/c", 12)
    rep.set_pid_after("/a", 10, "x")
    rep.set_pid_after("/b", None, "/t: all floats NaN")
    rep.set_pid_after("/c", 99, "/t2: empty image")
    rep.add_log({"node": "/a", "level": 8, "msg": "bad input", "during": "/t"})
    rep.add_log({"node": "/c", "level": 8, "msg": "Characters replaced when decoding message x", "during": "/t"})
    rep.add_input("topic", "/t", "std_msgs/String", ["/a", "/b"], 5, connected=["/a", "/b"])
    d = rep.to_dict()
    s = d["summary"]
    assert [x["node"] for x in s["nodes_died"]] == ["/b", "/c"]
    assert s["nodes_died"][1]["restarted"] and s["nodes_died"][0]["died_on"] == "/t: all floats NaN"
    assert s["silent_nodes"] == ["/b", "/c"], "a rospy decoding error does not count as the node's own"
    assert s["malformed_inputs_tried"] == 5 and not s["all_survived"]
    assert "/b <- /t" in s["silent_inputs"] and "/a <- /t" not in s["silent_inputs"]


def test_robustness_report_counts(tmp_path):
    rep = FuzzReport()
    rep.add_node("/a", 1)
    rep.add_input("topic", "/t", "x/Y", ["/a"], 7)
    scen = [{"kind": "link_cut", "target": "2", "survived": True, "detail": "ok"},
            {"kind": "link_cut_permanent", "target": "3", "survived": False, "detail": "never noticed"},
            {"kind": "crash", "target": "/central_unit", "survived": True, "detail": "ok"}]
    r = robustness_report(rep.to_dict(), scen, {"fires_extinguished": 5, "fires_total": 8}, robots_lost=["3"])
    assert (r["link_losses"], r["link_losses_survived"], r["crashes"], r["crashes_survived"]) == (2, 1, 1, 1)
    assert r["malformed_inputs_tried"] == 7 and r["fires_put_out"] == 5 and r["robots_lost"] == ["3"]
    assert r["failures"] == ["link_cut_permanent 3: never noticed"]
    text = format_robustness(r)
    assert "link losses survived: 1/2" in text and "FAILED" in text
    bumped = robustness_report(None, [], {"fires_extinguished": 1, "fires_total": 8, "crashes": ["1 hit 2"]})
    assert bumped["failures"] == ["collisions during the mission: ['1 hit 2']"]
    write_json(str(tmp_path / "r" / "report.json"), r)
    assert json.loads((tmp_path / "r" / "report.json").read_text())["crashes"] == 1


def test_merge_fuzz_reports():
    from mbzirc_robustness.report import merge_fuzz_reports
    a, b = FuzzReport(), FuzzReport()
    a.add_node("/a", 1)
    a.add_input("topic", "/t", "x/Y", ["/a"], 3)
    b.add_node("/b", 2)
    b.set_pid_after("/b", None, "/u: raw")
    b.add_input("service", "/u", "x/S", ["/b"], 4, outcomes=[("raw", "timeout")] * 4)
    m = merge_fuzz_reports([a.to_dict(), b.to_dict()])
    assert m["summary"]["malformed_inputs_tried"] == 7 and m["summary"]["nodes"] == 2
    assert [d["node"] for d in m["summary"]["nodes_died"]] == ["/b"] and not m["summary"]["all_survived"]
    assert merge_fuzz_reports([]) is None


def test_agent_log_window_finds_heartbeat_reaction_or_silence():
    from datetime import datetime
    lines = ["[rosout][INFO] 2026-11-21 08:51:29,182: [search_facade] GOING: holder 1/3\n",
             "[rospy.internal][INFO] 2026-11-21 08:51:30,000: topic[/x] removing connection\n",
             "[rosout][WARNING] 2026-11-21 08:51:40,100: central unit heartbeat lost: stopping the task safely\n",
             "[rosout][INFO] 2026-11-21 08:53:00,000: later\n"]
    w = F.agent_log_window(lines, datetime(2026, 11, 21, 8, 51, 35), datetime(2026, 11, 21, 8, 52, 0))
    assert w["lines"] == 1 and w["noticed_heartbeat_loss"]
    assert w["heartbeat_lines"] == ["08:51:40 WARNING: central unit heartbeat lost: stopping the task safely"]
    quiet = F.agent_log_window(lines, datetime(2026, 11, 21, 8, 51, 41), datetime(2026, 11, 21, 8, 52, 30))
    assert quiet["lines"] == 0 and not quiet["noticed_heartbeat_loss"]


def test_floor_released_while_silent_and_given_back_after_return_is_fine():
    h = [status(10, {"2": True, "0": True}, {"2": "2"})] + \
        [status(t, {"2": False, "0": True}, {}) for t in range(26, 81, 10)] + \
        [status(90, {"2": True, "0": True}, {"2": "2"}, tasks={"2": "x"})]
    r = F.evaluate_link_cut(h, "2", t_cut=20, t_restore=80)
    assert r["survived"] and r["floors_reassigned"] == ["f2"], r


def test_status_gap_of_a_scheduled_central_unit_kill_is_not_the_cuts():
    h = [status(t, {"3": t < 25}, {}) for t in (10, 25, 30, 35)] + [status(t, {"3": False}, {}) for t in (70, 75)]
    assert not F.evaluate_link_cut(h, "3", t_cut=20, t_restore=None)["survived"]
    r = F.evaluate_link_cut(h, "3", t_cut=20, t_restore=None, central_unit_kills=[40.0])
    assert r["survived"], r


def test_compare_tracks_after_an_estimator_restart():
    before = {1: 4, 2: 1, 3: 3, 5: 0}
    assert F.compare_tracks(before, dict(before))["same"]
    aged = F.compare_tracks(before, {1: 4, 2: 3, 3: 1, 5: 0, 6: 1})     # ACTIVE <-> LOST, a new track
    assert aged["same"] and aged["status_changes"] == {"2": [1, 3], "3": [3, 1]}
    empty = F.compare_tracks(before, {})
    assert not empty["same"] and empty["missing_ids"] == [1, 2, 3, 5] and "4 of 4 ids gone" in empty["detail"]
    lost_final = F.compare_tracks(before, {1: 1, 2: 1, 3: 3, 5: 0})     # EXTINGUISHED forgotten
    assert not lost_final["same"] and "statuses changed" in lost_final["detail"]


def _log(*lines):
    from datetime import datetime
    return F.agent_log_window([f"[rosout][WARNING] 2026-11-21 10:{x},000: {text}\n" for x, text in lines],
                              datetime(2026, 11, 21, 10, 0, 0), datetime(2026, 11, 21, 11, 0, 0))


def test_judge_agent_reaction_permanent_cut():
    from datetime import datetime
    cut, end = datetime(2026, 11, 21, 10, 0, 0), datetime(2026, 11, 21, 10, 3, 0)
    good = _log(("00:05", "central unit heartbeat lost: stopping the task safely"),
                ("01:10", "State machine transitioning 'DEFAULT':'go_home_and_refill'-->'go_home_and_refill'"))
    assert good["events"]["heartbeat_lost"] == ["2026-11-21T10:00:05.000"]
    v = F.judge_agent_reaction(good, cut, None, end, expect_home=True)
    assert v["agent_ok"] and v["agent_checked"] == ["heartbeat_lost", "return_home"], v
    silent = _log(("00:01", "[follow_path/go_to] MOVING"))
    v = F.judge_agent_reaction(silent, cut, None, end, expect_home=True)
    assert not v["agent_ok"] and len(v["agent_problems"]) == 2
    stuck = _log(("00:05", "central unit heartbeat lost: stopping the task safely"))
    v = F.judge_agent_reaction(stuck, cut, None, end, expect_home=True)
    assert not v["agent_ok"] and "going home" in v["agent_problems"][0]
    assert F.judge_agent_reaction(stuck, cut, None, end, expect_home=False)["agent_ok"]      # landed: stays
    early = _log(("00:02", "[go_home_and_refill/go_to] MOVING"), ("00:05", "heartbeat lost"))  # before the loss
    assert not F.judge_agent_reaction(early, cut, None, end, expect_home=True)["agent_ok"]
    late = _log(("00:05", "heartbeat lost"), ("02:30", "transitioning 'DEFAULT':'go_home_and_refill'"))  # 150 s
    assert not F.judge_agent_reaction(late, cut, None, end, expect_home=True)["agent_ok"]
    blocked = _log(("00:05", "heartbeat lost"), ("01:55", "State machine transitioning 'follow_path':'error'-->'DEFAULT'"),
                   ("02:00", "State machine transitioning 'DEFAULT':'go_home_and_refill'-->'go_home_and_refill'"))
    assert blocked["events"]["task_ended"] == ["2026-11-21T10:01:55.000"]                 # not the go_home line
    assert not F.judge_agent_reaction(blocked, cut, None, end, expect_home=True)["agent_ok"]  # idle: due at 65 s
    v = F.judge_agent_reaction(blocked, cut, None, end, expect_home=True, busy_at_cut=True)  # its task ended late
    assert v["agent_ok"] and "return_home" in v["agent_checked"], v
    v = F.judge_agent_reaction(stuck, cut, None, end, expect_home=True, busy_at_cut=True)    # task never ended
    assert not v["agent_ok"] and "never ended" in v["agent_problems"][0] and not v["agent_unverified"]
    named = _log(("00:05", "heartbeat lost"), ("01:10", "go_home_and_refill failed: no pose"),
                 ("01:11", "[go_home_and_refill/go_to] MOVING"))               # names the task, never started it
    assert "return_home" not in named["events"]
    assert not F.judge_agent_reaction(named, cut, None, end, expect_home=True)["agent_ok"]
    ended = _log(("00:05", "heartbeat lost"), ("00:06", "transitioning 'follow_path':'preempted'-->'DEFAULT'"))
    v = F.judge_agent_reaction(ended, cut, None, end, expect_home=True, busy_at_cut=True)     # ended, never went
    assert not v["agent_ok"] and "by 80 s" in v["agent_problems"][0]
    short_end = datetime(2026, 11, 21, 10, 0, 30)                                        # too short to tell
    assert F.judge_agent_reaction(stuck, cut, None, short_end, expect_home=True)["agent_checked"] == ["heartbeat_lost"]


def test_judge_agent_reaction_temporary_cut_needs_heartbeat_back():
    from datetime import datetime
    cut, restore, end = (datetime(2026, 11, 21, 10, 0, s) for s in (0, 20, 0))
    end = datetime(2026, 11, 21, 10, 3, 0)
    back = _log(("00:05", "central unit heartbeat lost"), ("00:30", "central unit heartbeat back: accepting goals"))
    v = F.judge_agent_reaction(back, cut, restore, end, expect_home=True)
    assert v["agent_ok"] and v["agent_checked"] == ["heartbeat_lost", "heartbeat_back"], v
    never = _log(("00:05", "central unit heartbeat lost"))
    assert "never logged the heartbeat back" in F.judge_agent_reaction(never, cut, restore, end, True)["agent_problems"][0]


# ---- made-up failing histories: each verdict must fail them (issue 20) ----------------------------------
def test_central_unit_that_sent_one_status_and_went_silent_fails_the_cut():
    h = [status(10, {"3": True, "1": True}, {"3": "3"}), status(26, {"3": False, "1": True}, {})]
    r = F.evaluate_link_cut(h, "3", t_cut=20, t_restore=None, t_end=120)
    assert not r["survived"] and "stopped" in r["detail"], r
    alive = h + [status(t, {"3": False, "1": True}, {"3": "1"}) for t in range(30, 121, 10)]
    assert F.evaluate_link_cut(alive, "3", t_cut=20, t_restore=None, t_end=120)["survived"]


def test_floor_released_and_never_retaken_fails():
    h = [status(10, {"2": True, "1": True}, {"2": "2"}, tasks={"1": "x"})] + \
        [status(t, {"2": False, "1": True}, {}) for t in range(26, 200, 10)]
    r = F.evaluate_link_cut(h, "2", t_cut=20, t_restore=None, t_end=200)
    assert not r["survived"] and r["floors_released_not_retaken"] == ["f2"] and "not taken again" in r["detail"]
    h2 = h[:4] + [status(t, {"2": False, "1": True}, {"2": "1"}) for t in range(56, 200, 10)]
    r2 = F.evaluate_link_cut(h2, "2", t_cut=20, t_restore=None, t_end=200)
    assert r2["survived"] and r2["floors_reassigned"] == ["f2"], r2


def test_floor_released_while_the_only_water_uav_left_works_another_floor_is_kept():
    """The one water UAV left (3) takes the floor priority's first floor (2) and the released floor 0 waits
    its turn; the UGV (0) and the blanket UAV (1), idle, cannot take a facade floor (a fault-suite run
    failed here although no robot could have taken it)."""
    agents = lambda t: {"2": False, "3": True, "0": True, "1": True}
    h = [status(10, {"2": True, "3": True, "0": True, "1": True}, {"0": "2", "2": "3"}, tasks={"3": "x"})] + \
        [status(t, agents(t), {"2": "3"}, tasks={"3": "x"}) for t in range(26, 200, 10)]
    for s in h:
        for r, kind, payload in (("0", "ugv", "water"), ("1", "uav", "blanket"), ("2", "uav", "water"),
                                 ("3", "uav", "water")):
            s[1]["agents"][r].update(kind=kind, payload=payload)
    r = F.evaluate_link_cut(h, "2", t_cut=20, t_restore=None, t_end=200)
    assert r["survived"] and r["floors_kept_no_free_robot"] == ["f0"], r
    for s in h[3:]:                              # the water UAV left idle and owning nothing: dropped
        s[1]["agents"]["3"]["task"] = ""
        s[1]["floor_owner"] = {}
    r2 = F.evaluate_link_cut(h, "2", t_cut=20, t_restore=None, t_end=200)
    assert not r2["survived"] and r2["floors_released_not_retaken"] == ["f0"], r2


def test_central_unit_restart_must_decide_again():
    before = [status(t, {"1": True}, {"1": "1"}, tasks={"1": "a"}) for t in (100, 110)]
    one_then_silent = before + [status(130, {"1": True}, {"1": "1"})]
    v = F.judge_decisions(one_then_silent, t_kill=115, t_end=250)
    assert not v["ok"] and "stopped again" in v["detail"]
    frozen = before + [status(t, {"1": True}, {"1": "1"}) for t in range(130, 251, 5)]   # statuses, no decision
    v = F.judge_decisions(frozen, t_kill=115, t_end=250)
    assert not v["ok"] and "no decision" in v["detail"]
    working = frozen[:6] + [status(t, {"1": True}, {"1": "1"}, tasks={"1": "b"}) for t in range(155, 251, 5)]
    v = F.judge_decisions(working, t_kill=115, t_end=250)
    assert v["ok"] and v["first_decision_after_s"] == 40.0, v
    assert not F.judge_decisions(before, t_kill=115, t_end=250)["ok"]


def test_clock_fault_and_flood_verdicts():
    v = F.judge_outputs({"/central_unit/heartbeat": 50.0, "/mbzirc2020_1/data_feed": 9.0}, t_fault=10.0,
                        expected=["/central_unit/heartbeat", "/mbzirc2020_1/data_feed", "/estimated_objects"])
    assert not v["ok"] and v["silent_outputs"] == ["/estimated_objects", "/mbzirc2020_1/data_feed"]
    assert F.judge_outputs({"/a": 12.0}, 10.0, ["/a"])["ok"]
    assert not F.judge_flood([0.2, 0.3, 40.0])["ok"]
    assert not F.judge_flood([])["ok"], "no /estimated_objects at all during the flood is a stall"
    assert F.judge_flood([0.2, 0.4])["ok"]
    assert not F.judge_flood([0.2], outputs_after=v)["ok"]


def test_restarted_node_must_be_wired_again():
    bus = [[1, "/ual_sim", "i", "TCPROS", "/mbzirc2020_2/teraranger_evo_thermal/raw_temp_array", True],
           [2, "/ual_sim", "i", "TCPROS", "/mbzirc2020_2/ual/pose", True],
           [3, "/agent", "o", "TCPROS", "/mbzirc2020_2/sensed_objects", True],
           [4, "/ual_sim", "i", "TCPROS", "/clock", True]]
    before = F.connected_inputs(bus)
    assert before == {"/mbzirc2020_2/teraranger_evo_thermal/raw_temp_array", "/mbzirc2020_2/ual/pose"}
    assert not F.judge_io_restored(before, set())["ok"], "a new pid alone is not a working detector"
    assert not F.judge_io_restored(before, F.connected_inputs(bus[1:]))["ok"]
    assert F.judge_io_restored(before, F.connected_inputs(bus))["ok"]


def test_region_manager_restart_and_mission_floor():
    assert not F.compare_regions({"1/go_to", "2/parked"}, {"2/parked"})["same"]
    assert F.compare_regions({"1/go_to"}, {"1/go_to", "3/x"})["same"]
    floor = F.mission_floor("short")
    assert F.judge_mission({"fires_extinguished": 0, "fires_total": 8}, ["3"], floor, expected_lost=["3"])
    assert F.judge_mission({"fires_extinguished": 5, "fires_total": 8}, ["1", "3"], floor, expected_lost=["3"])
    assert F.judge_mission({"fires_extinguished": 5, "fires_total": 8}, ["2"], floor, expected_lost=["3"])
    assert F.judge_mission(None, [], floor)
    assert F.judge_mission({"fires_extinguished": 5, "fires_total": 8}, ["3"], floor, expected_lost=["3"]) == []


def test_task_exception_verdict_fails_a_zombie_or_failed_agent():
    h = [status(t, {"1": True}, {}, tasks={"1": "x" if t > 120 else ""}) for t in range(100, 160, 5)]
    flowing = [(float(k), "") for k in range(0, 45)]
    v = F.judge_working(flowing, h, "1", t_inject=105, watch_wall_s=45)
    assert v["ok"] and v["task_after"] == "x", v
    zombie = [(float(k), "") for k in range(0, 5)]                 # feeds stopped soon after the injection
    assert not F.judge_working(zombie, h, "1", 105, 45)["ok"]
    failed = flowing + [(44.0, "FAILED: state machine died 4 times")]
    assert "declared itself failed" in F.judge_working(failed, h, "1", 105, 45)["detail"]
    dead = h + [status(200, {"1": False}, {})]
    assert not F.judge_working(flowing, dead, "1", 105, 45)["ok"]


def test_resumed_regions_are_read_from_the_managers_log():
    from datetime import datetime
    lines = ["[rosout][INFO] 2026-11-24 02:15:25,418: region manager: no state file x; starting with no reservations\n",
             "[rosout][INFO] 2026-11-24 02:17:05,215: region manager: resumed 3 reservations from /o/regions.json "
             "(regions saved at t=266.7 s): 1/go_to, 2/hold, 3/go_to\n"]
    got = F.resumed_regions(lines, datetime(2026, 11, 24, 2, 16, 50))
    assert got == {"1/go_to", "2/hold", "3/go_to"}
    assert F.compare_regions({"1/go_to", "2/hold"}, got)["same"]
    assert not F.compare_regions({"1/go_to", "4/x"}, got)["same"]
    assert F.resumed_regions(lines, datetime(2026, 11, 24, 2, 18, 0)) is None


def test_a_box_freed_between_the_last_regions_and_the_kill_is_not_lost_but_an_unlogged_one_is():
    """The run that failed with "reservations lost: ['2/go_to']": the last /regions before the kill showed
    table 41 with 2/go_to; UAV 2 freed it (table 42, logged, saved) just before the kill; the respawned
    manager resumed table 42. Only boxes the old manager logged as removed after the table shown are
    excused: a box of the shown table missing without such a line, or a resumed table older than the one
    shown, is still a loss."""
    from datetime import datetime
    old = ["[rosout][INFO] 2026-11-24 02:16:40,100: region manager: table 40: removed 1/go_to\n",
           "[rosout][INFO] 2026-11-24 02:16:48,902: region manager: table 42: removed 2/go_to\n"]
    new = ["[rosout][INFO] 2026-11-24 02:16:53,215: region manager: resumed 4 reservations from /o/regions.json "
           "(regions saved at t=161.4 s, table 42): 1/parked, 2/hold, 3/go_to, 3/hold\n"]
    before = {"1/parked", "2/hold", "2/go_to", "3/go_to", "3/hold"}
    resumed, table = F.resumed_table(old + new, datetime(2026, 11, 24, 2, 16, 49))
    assert table == 42 and resumed == before - {"2/go_to"}
    assert not F.compare_regions(before, resumed)["same"], "without table numbers: judged as before"
    removed = F.removed_between(old + new, 41, table)
    assert removed == {"2/go_to"}
    v = F.compare_regions(before, resumed, 41, table, removed)
    assert v["same"] and v["freed_meanwhile"] == ["2/go_to"], v
    lost = resumed - {"3/hold"}                                   # a live box truly lost
    v = F.compare_regions(before, lost, 41, table, removed)
    assert not v["same"] and v["missing"] == ["3/hold"], v
    assert not F.compare_regions(before, resumed, 41, table, F.removed_between(old, 39, 40))["same"]
    v = F.compare_regions(before, before, 41, 40, set())         # resumed a table older than one shown
    assert not v["same"] and "older" in v["detail"], v
    assert F.shown_table("table 41") == 41 and F.shown_table("") is None


def test_a_lazy_node_without_demand_may_leave_its_inputs_unconnected():
    """A respawned circle detector (~lazy) subscribes to its cameras only while a task demands holes: with no
    subscriber on its outputs, unconnected inputs are its design; with one, they are a failure."""
    before = {"/cam/image", "/cam/depth"}
    assert F.judge_io_restored(before, set(), outputs_wanted=False)["ok"]
    assert not F.judge_io_restored(before, set(), outputs_wanted=True)["ok"]
    bus = [[1, "/agent", "o", "TCPROS", "/x/middle_hole", 1, ""], [2, "/rosout", "o", "TCPROS", "/rosout", 1, ""]]
    assert F.connected_outputs(bus) == {"/x/middle_hole"} and F.connected_outputs(bus[1:]) == set()
    always_on = F.LAZY_NODES["circle_detector"]
    objects = [[3, "/object_estimator", "o", "TCPROS", "/x/sensed_objects", 1, ""]]
    assert F.connected_outputs(objects + bus[1:], always_on) == set()
    assert F.connected_outputs(objects + bus, always_on) == {"/x/middle_hole"}
