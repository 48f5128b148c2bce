"""Commands of the strategy become the agents' action goals (message classes only, no master)."""
import math

import rospy

from mbzirc_central_unit import constants as C
from mbzirc_central_unit.central_unit import ACTION_TYPES, goal_msg, result_dict
from mbzirc_central_unit.strategy import Command
from mbzirc_comm_objs import msg as cmsg


def test_every_task_has_its_action_type():
    for task in C.UAV_TASKS + C.UGV_TASKS:
        assert hasattr(cmsg, ACTION_TYPES[task] + "Goal")


def test_paths_and_poses_become_pose_stamped_in_the_arena_frame():
    stamp = rospy.Time(12, 0)
    g = goal_msg(Command("2", C.SEARCH_FACADE, {"floor": 2, "path": [(1.0, 2.0, 3.0, math.pi / 2)],
                                                 "_floor": 2}), stamp)
    assert isinstance(g, cmsg.SearchFacadeGoal) and g.floor == 2 and len(g.path) == 1
    p = g.path[0]
    assert p.header.frame_id == "arena" and p.header.stamp == stamp
    assert (p.pose.position.x, p.pose.position.y, p.pose.position.z) == (1.0, 2.0, 3.0)
    assert math.isclose(2 * math.atan2(p.pose.orientation.z, p.pose.orientation.w), math.pi / 2)
    e = goal_msg(Command("3", C.ENTER_BUILDING, {"floor": 1, "entry": (9.0, 12.5, 7.5, 0.0)}), stamp)
    assert e.entry.pose.position.z == 7.5 and e.entry.pose.orientation.w == 1.0
    f = goal_msg(Command("2", C.GO_TO_FACADE_FIRE, {"fire_id": 7, "distance": 2.0}), stamp)
    assert f.fire_id == 7 and math.isclose(f.distance, 2.0)


def test_result_dict_reads_the_fields_we_use():
    r = cmsg.ExtinguishFacadeFireResult(message="fire 7 extinguished", extinguished=True, water_left=0.5)
    assert result_dict(r) == {"message": "fire 7 extinguished", "extinguished": True, "water_left": 0.5}
    s = cmsg.SearchFacadeResult(message="x", fire_ids=[3, 4])
    assert result_dict(s)["fire_ids"] == [3, 4]
    assert result_dict(None) == {}
