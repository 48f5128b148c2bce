"""The message, service and action definitions against the design (docs/architecture.md).

The types that cross the original system's interfaces must be wire-identical to the original: same field
names, types, order and constants, hence the same md5sum. A changed comment is harmless; a changed field,
type or constant breaks every node of the original that talks to ours, and these tests catch it.
"""
import subprocess

import pytest

from mbzirc_comm_objs import msg as M, srv as S
from uav_abstraction_layer import msg as UM, srv as US

# The md5 table at the end of docs/architecture.md.
WIRE_MD5 = {
    M.ObjectDetection: "afa29357bc81a2722453a0e50fa8a374",
    M.ObjectDetectionList: "f1202b9827b40df31c327bbe8356bb82",
    M.ThermalImage: "38550731ba5330188873bd88fcab7a8c",
    S.CheckFire: "c77a05c592469254650b303431850372",
    S.AskForRegion: "ab14e93feda4801c8c0c6f2d71622b78",
    S.FreeRegions: "1cb9cdfe5f845d3c139b39ddfba62c77",
    S.SetObjectStatus: "f3ef86c724949b7eef1d001e734ac36b",
    UM.State: "533576484916e98b63315c3434a12ab9",
    US.TakeOff: "92f7691c5527d6fb3cc35d20a69e7778",
    US.Land: "c37d0c321494079f6ac6aae0680a10e1",
    US.GoToWaypoint: "1b4a030ed9ba0e5a2761567aa99a96b7",
    US.SetHome: "27f767d7f04b6ba462fa116e03c0b202",
}


@pytest.mark.parametrize("cls,md5", WIRE_MD5.items(), ids=lambda v: getattr(v, "_type", v))
def test_wire_md5(cls, md5):
    assert cls._md5sum == md5


def fields(cls):
    return list(zip(cls.__slots__, cls._slot_types))


def test_object_detection_fields_and_constants():
    assert fields(M.ObjectDetection) == [
        ("header", "std_msgs/Header"),
        ("pose", "geometry_msgs/PoseWithCovariance"),
        ("point_of_interest", "geometry_msgs/Point"),
        ("relative_position", "geometry_msgs/Point"),
        ("relative_yaw", "float32"),
        ("scale", "geometry_msgs/Vector3"),
        ("type", "uint8"),
        ("color", "uint8"),
        ("image_detection", "mbzirc_comm_objs/ThermalImage"),
        ("is_cropped", "bool"),
    ]
    types = dict(TYPE_UNKNOWN=0, TYPE_BALLOON=1, TYPE_BALL=2, TYPE_BRICK=4, TYPE_BRICK_TRACK=5,
                 TYPE_UCHANNEL=6, TYPE_LWALL=7, TYPE_FIRE=8, TYPE_HOLE=9, TYPE_PASSAGE=10)
    colors = dict(COLOR_UNKNOWN=0, COLOR_RED=1, COLOR_GREEN=2, COLOR_BLUE=3, COLOR_ORANGE=4, COLOR_WHITE=5,
                  COLOR_FIRE=6)
    for name, value in {**types, **colors, "BRICK_COLORS": 4}.items():
        assert getattr(M.ObjectDetection, name) == value, name
    # BRICK_COLORS is signed in the original: the md5 depends on it.
    assert "int8 BRICK_COLORS=4" in M.ObjectDetection._full_text.replace(" = ", "=")


def test_thermal_image_fields_and_constants():
    assert fields(M.ThermalImage) == [
        ("camera_direction", "uint8"), ("img_height", "uint8"), ("img_width", "uint8"),
        ("u", "float32"), ("v", "float32"), ("height", "float32"), ("width", "float32"), ("depth", "float32"),
    ]
    assert (M.ThermalImage.CAMERA_DIRECTION_UNKNOWN, M.ThermalImage.CAMERA_DIRECTION_FORWARD,
            M.ThermalImage.CAMERA_DIRECTION_DOWNWARD) == (0, 1, 2)


def test_detection_list_and_services():
    assert fields(M.ObjectDetectionList) == [
        ("agent_id", "string"), ("stamp", "time"), ("objects", "mbzirc_comm_objs/ObjectDetection[]")]
    assert fields(S.CheckFireRequest) == [] and fields(S.CheckFireResponse) == [("fire_detected", "bool")]
    assert fields(S.AskForRegionRequest) == [
        ("agent_id", "string"), ("label", "string"),
        ("min_corner", "geometry_msgs/PointStamped"), ("max_corner", "geometry_msgs/PointStamped")]
    assert fields(S.AskForRegionResponse) == [("success", "bool")]
    assert fields(S.FreeRegionsRequest) == [("agent_id", "string"), ("label", "string"), ("free_all", "bool")]
    assert fields(S.SetObjectStatusRequest) == [
        ("object_id", "int16"), ("object_status", "uint8"), ("object_type", "uint8")]
    assert fields(S.SetObjectStatusResponse) == []
    r = S.SetObjectStatusRequest
    assert (r.INACTIVE, r.ACTIVE, r.DETECTED, r.LOST) == (0, 1, 2, 3)
    assert fields(S.GetCostToGoToRequest) == [("waypoint", "geometry_msgs/PoseStamped")]
    assert fields(S.GetCostToGoToResponse) == [("cost", "float32")]


def test_estimator_object_status_matches_set_object_status():
    """Object is our extension; its STATUS_ values must agree with SetObjectStatus's."""
    r = S.SetObjectStatusRequest
    o = M.Object
    assert (o.STATUS_INACTIVE, o.STATUS_ACTIVE, o.STATUS_DETECTED, o.STATUS_LOST) == (
        r.INACTIVE, r.ACTIVE, r.DETECTED, r.LOST)
    assert o.STATUS_EXTINGUISHED not in (r.INACTIVE, r.ACTIVE, r.DETECTED, r.LOST)
    assert ("id", "uint16") in fields(o) and ("status", "uint8") in fields(o)
    assert fields(M.ObjectList) == [("stamp", "time"), ("objects", "mbzirc_comm_objs/Object[]")]


def test_ual_state_constants_and_services():
    s = UM.State
    assert [s.UNINITIALIZED, s.LANDED_DISARMED, s.LANDED_ARMED, s.TAKING_OFF, s.FLYING_AUTO, s.FLYING_MANUAL,
            s.LANDING] == list(range(7))
    assert fields(s) == [("state", "uint8")]
    assert fields(US.TakeOffRequest) == [("height", "float32"), ("blocking", "bool")]
    assert fields(US.LandRequest) == [("blocking", "bool")]
    assert fields(US.GoToWaypointRequest) == [("waypoint", "geometry_msgs/PoseStamped"), ("blocking", "bool")]
    assert fields(US.SetHomeRequest) == [("set_z", "bool")]


def test_every_action_reports_a_message():
    """Each agent task is an action whose result says in words what happened (style.md)."""
    import mbzirc_comm_objs.msg as all_msgs
    actions = [n[:-len("Action")] for n in dir(all_msgs) if n.endswith("Action") and not n.startswith("_")
               and not n.endswith("ActionResult") and not n.endswith("ActionFeedback")]
    assert {"TakeOff", "Land", "GoTo", "FollowPath", "GoToFacadeFire", "ExtinguishFacadeFire",
            "LookForGroundFires", "ExtinguishGroundFire"} <= set(actions)
    for a in actions:
        result = getattr(all_msgs, a + "Result")
        assert "message" in result.__slots__, a
        assert "state" in getattr(all_msgs, a + "Feedback").__slots__, a


def test_rosmsg_md5_cli_agrees():
    """The command users type must print the same as the generated classes."""
    out = subprocess.run(["rosmsg", "md5", "mbzirc_comm_objs/ObjectDetection"], capture_output=True, text=True,
                         timeout=60)
    assert out.stdout.strip() == WIRE_MD5[M.ObjectDetection], out.stderr
    out = subprocess.run(["rossrv", "md5", "uav_abstraction_layer/GoToWaypoint"], capture_output=True,
                         text=True, timeout=60)
    assert out.stdout.strip() == WIRE_MD5[US.GoToWaypoint], out.stderr
