"""The state the page draws, built from messages: poses, staleness, tasks, fires, regions, bad input."""
import math

from mbzirc_comm_objs.msg import Object, TakeOffActionFeedback, TakeOffActionGoal, TakeOffActionResult
from mbzirc_comm_objs.msg import SearchFacadeActionGoal
from geometry_msgs.msg import PoseStamped
from smach_msgs.msg import SmachContainerStatus
from std_msgs.msg import Header, String
from ual_sim.msg import Score
from visualization_msgs.msg import Marker, MarkerArray

from mbzirc_ground_station.state import GroundStationState

from msgs import cu_status, feed, fires


def robot(frame, rid):
    return next(r for r in frame["robots"] if r["id"] == rid)


def test_robot_pose_heading_altitude_and_payload_from_data_feed():
    s = GroundStationState(robot_ids=["1", "2"])
    s.apply("/mbzirc2020_2/data_feed", feed("2", 3.0, 4.0, 6.0, yaw=1.0, water=1.25), 10.0)
    f = s.frame(10.05)
    r = robot(f, "2")
    assert r["pose"] == {"x": 3.0, "y": 4.0, "z": 6.0, "yaw": 1.0, "stamp": 0.0}
    assert r["ual_state"] == "FLYING_AUTO" and r["water"] == 1.25 and r["link"]["status"] == "ok"
    assert robot(f, "1")["link"]["status"] == "unknown" and robot(f, "1")["pose"] is None


def test_heartbeat_age_late_then_stale():
    s = GroundStationState()
    s.apply("/mbzirc2020_1/data_feed", feed("1", payload="blanket"), 5.0)
    assert robot(s.frame(6.5), "1")["link"] == {"age": 1.5, "status": "late"}
    r = robot(s.frame(8.0), "1")
    assert r["link"]["status"] == "stale" and r["pose_status"] == "stale"
    assert r["ual_state"] == "unknown" and r["water"] is None and r["blanket"] is None


def test_feed_without_pose_frame_is_unknown_pose():
    s = GroundStationState()
    s.apply("/mbzirc2020_3/data_feed", feed("3", frame=""), 1.0)
    assert robot(s.frame(1.0), "3")["pose"] is None


def test_nan_pose_is_unknown_and_does_not_extend_the_track():
    s = GroundStationState()
    s.apply("/mbzirc2020_2/data_feed", feed("2", 1.0, 1.0, 2.0), 1.0)
    s.apply("/mbzirc2020_2/data_feed", feed("2", float("nan"), 1.0, 2.0), 1.1)
    f = s.frame(1.1, tracks=True)
    assert robot(f, "2")["pose"] is None and f["tracks"]["2"] == [(1.0, 1.0)]


def test_track_keeps_a_point_per_step_and_stays_bounded():
    s = GroundStationState(track_step=0.5, track_limit=50)
    for i in range(1000):
        s.apply("/mbzirc2020_2/data_feed", feed("2", 0.1 * i, 0.0, 5.0), 0.1 * i)
    pts = s.frame(tracks=True)["tracks"]["2"]
    assert 10 <= len(pts) <= 51
    assert pts[0] == (0.0, 0.0) and pts[-1][0] > 95.0
    assert all(b[0] > a[0] for a, b in zip(pts, pts[1:]))


def test_malformed_message_is_counted_logged_and_harmless():
    s = GroundStationState()
    s.apply("/central_unit/status", String(data="{not json"), 1.0)
    s.apply("/mbzirc2020_2/data_feed", String(data="wrong type"), 1.0)
    f = s.frame(1.0)
    assert f["bad_messages"] == {"/central_unit/status": 1, "/mbzirc2020_2/data_feed": 1}
    assert f["cu"]["status"] == "unknown"
    assert any("malformed" in e["text"] for e in f["log"])


def test_fires_kind_floor_status_and_changes_logged():
    s = GroundStationState()
    s.apply("/estimated_objects", fires((1, Object.SUBTYPE_FACADE, Object.STATUS_ACTIVE, 24.2, 8.2, 8.25),
                                        (2, Object.SUBTYPE_GROUND, Object.STATUS_LOST, 1.0, 14.0, 0.1)), 3.0)
    s.apply("/estimated_objects", fires((1, Object.SUBTYPE_FACADE, Object.STATUS_EXTINGUISHED, 24.2, 8.2, 8.25),
                                        (2, Object.SUBTYPE_GROUND, Object.STATUS_LOST, 1.0, 14.0, 0.1)), 4.0)
    f = s.frame(4.0)
    assert [(x["id"], x["kind"], x["floor"], x["status"]) for x in f["fires"]] == [
        (1, "facade", 1, "EXTINGUISHED"), (2, "ground", 0, "LOST")]
    texts = [e["text"] for e in f["log"]]
    assert texts == ["fire 1 (facade, floor 1): ACTIVE", "fire 2 (ground, floor 0): LOST",
                     "fire 1 (facade, floor 1): EXTINGUISHED"]
    assert s.frame(20.0)["fires_status"] == "stale"


def test_task_goal_feedback_result_and_log():
    s = GroundStationState()
    g = SearchFacadeActionGoal()
    g.goal.path = [PoseStamped(), PoseStamped()]
    s.apply("/mbzirc2020_3/search_facade_action/goal", g, 2.0)
    task = robot(s.frame(2.0), "3")["task"]
    assert task["name"] == "search_facade" and "2 poses" in task["goal"]
    s.apply("/mbzirc2020_3/take_off_action/goal", TakeOffActionGoal(), 3.0)
    fb = TakeOffActionFeedback()
    fb.feedback.state, fb.feedback.message = "MOVING", "climbing to 3 m"
    s.apply("/mbzirc2020_3/take_off_action/feedback", fb, 3.5)
    res = TakeOffActionResult()
    res.status.status, res.result.message = 3, "at 3.0 m"
    s.apply("/mbzirc2020_3/take_off_action/result", res, 4.0)
    task = robot(s.frame(4.0), "3")["task"]
    assert task["name"] == "take_off" and task["feedback"]["state"] == "MOVING"
    assert task["result"] == {"status": "SUCCEEDED", "message": "at 3.0 m", "t": 4.0}
    assert [e["source"] for e in s.frame(4.0)["log"]] == ["goal", "goal", "result"]


def test_smach_state_chain_from_nested_containers():
    s = GroundStationState()
    s.apply("/mbzirc2020_1/smach/container_status",
            SmachContainerStatus(path="/SM_ROOT", active_states=["extinguish"]), 1.0)
    s.apply("/mbzirc2020_1/smach/container_status",
            SmachContainerStatus(path="/SM_ROOT/extinguish", active_states=["SHOOTING"]), 1.0)
    assert robot(s.frame(1.0), "1")["smach"] == "extinguish/SHOOTING"


def test_central_unit_decisions_logged_and_per_robot():
    s = GroundStationState()
    s.apply("/central_unit/status", cu_status(1.0, {"2": {"alive": True, "task": "search_facade",
                                                          "doing": "floor 2"}}, floor_owner={"2": 2}), 1.0)
    s.apply("/central_unit/status", cu_status(1.5, {"2": {"alive": True, "task": "search_facade",
                                                          "doing": "floor 2"}}, floor_owner={"2": 2}), 1.5)
    s.apply("/central_unit/heartbeat", Header(), 1.5)
    f = s.frame(2.0)
    assert [e["text"] for e in f["log"]] == ["UAV 2: search_facade - floor 2", 'floor owner: {"2": 2}']
    assert robot(f, "2")["cu"]["task"] == "search_facade"
    assert f["cu"]["status"] == "ok" and f["cu"]["heartbeat"] == "ok"
    f = s.frame(10.0)
    assert f["cu"]["status"] == "stale" and robot(f, "2")["cu"] is None


def test_regions_from_markers_and_deleteall():
    s = GroundStationState()
    m = Marker(type=Marker.CUBE, action=Marker.ADD, id=0, ns="2/go_to")
    m.pose.position.x, m.pose.position.y, m.pose.position.z = 1.0, 2.0, 3.0
    m.scale.x, m.scale.y, m.scale.z = 2.0, 4.0, 2.0
    s.apply("/regions", MarkerArray(markers=[Marker(action=Marker.DELETEALL), m]), 1.0)
    assert s.frame(1.0)["regions"] == [{"agent": "2", "label": "go_to", "rect": [0.0, 0.0, 2.0, 4.0],
                                        "z": [2.0, 4.0]}]
    s.apply("/regions", MarkerArray(markers=[Marker(action=Marker.DELETEALL)]), 2.0)
    assert s.frame(2.0)["regions"] == []


def test_score_is_ground_truth_and_hidden_when_absent_or_stale():
    s = GroundStationState()
    assert s.frame(0.0)["ground_truth"] is None
    s.apply("/sim/score", Score(score=2.5, max_score=8, fires_extinguished=2, elapsed=100.0, time_left=1100.0), 100.0)
    gt = s.frame(100.5)["ground_truth"]
    assert gt["score"] == 2.5 and gt["fires_extinguished"] == 2
    assert s.frame(110.0)["ground_truth"] is None


def test_sim_time_going_back_is_a_new_trial():
    s = GroundStationState()
    s.apply("/mbzirc2020_2/data_feed", feed("2", 5.0, 5.0, 5.0), 100.0)
    s.apply("/mbzirc2020_1/data_feed", feed("1", 1.0, 1.0, 0.0), 2.0)
    f = s.frame(2.0)
    assert [r["id"] for r in f["robots"]] == ["1"] and "new trial" in f["log"][0]["text"]


def test_unrelated_topics_and_non_finite_times_are_ignored():
    s = GroundStationState()
    s.apply("/mbzirc2020_2/scan", object(), 1.0)
    s.apply("/mbzirc2020_2/data_feed", feed("2"), math.nan)
    assert s.messages == 0 and s.frame()["robots"] == []
