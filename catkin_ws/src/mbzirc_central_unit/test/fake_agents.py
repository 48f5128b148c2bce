"""Fake agents over ROS for the central unit's integration test: the action servers of every task, the
data_feeds and /estimated_objects, driven by the toy executor of the unit tests (instant task effects)."""
from __future__ import annotations

import math
import os
import sys
import threading

import actionlib
import rospy
from mbzirc_comm_objs import msg as cmsg
from mbzirc_comm_objs.srv import FreeRegions, FreeRegionsResponse

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "unit"))
from fake_mission import FakeMission  # noqa: E402

from mbzirc_central_unit import constants as C  # noqa: E402
from mbzirc_central_unit.central_unit import ACTION_TYPES  # noqa: E402
from mbzirc_central_unit.strategy import Command  # noqa: E402


def _pose(p) -> tuple:
    q = p.pose.orientation
    return (p.pose.position.x, p.pose.position.y, p.pose.position.z, 2 * math.atan2(q.z, q.w))


def goal_dict(goal) -> dict:
    out = {}
    for k in goal.__slots__:
        v = getattr(goal, k)
        if isinstance(v, list):
            out[k] = [_pose(p) for p in v]
        elif hasattr(v, "pose"):
            out[k] = _pose(v)
        else:
            out[k] = v
    return out


class FakeAgents:
    """Serves every task of every fake agent; `silent` agents stop publishing their data_feed."""

    def __init__(self, task_time: float = 0.2) -> None:
        self.mission = FakeMission()
        self.lock = threading.Lock()
        self.silent: set[str] = set()
        self.task_time = task_time
        self.received: list[tuple[float, str, str]] = []
        self.busy: dict[str, str] = {}
        self.servers = []
        for aid, a in self.mission.agents.items():
            tasks = C.UAV_TASKS if a.is_uav else C.UGV_TASKS
            for task in tasks:
                action = getattr(cmsg, ACTION_TYPES[task] + "Action")
                srv = actionlib.SimpleActionServer(f"/{C.robot_ns(aid)}/{task}_action", action,
                                                   execute_cb=self._make_cb(aid, task), auto_start=False)
                srv.start()
                self.servers.append(srv)
        self.feeds = {aid: rospy.Publisher(f"/{C.robot_ns(aid)}/data_feed", cmsg.AgentDataFeed, queue_size=1)
                      for aid in self.mission.agents}
        self.objects = rospy.Publisher("/estimated_objects", cmsg.ObjectList, queue_size=1)
        self.freed: list[str] = []
        self.free_srv = rospy.Service("/free_regions", FreeRegions, self._on_free)
        self.timer = rospy.Timer(rospy.Duration(0.1), self._publish)

    def _on_free(self, req):
        self.freed.append(req.agent_id)
        return FreeRegionsResponse(success=True)

    def _make_cb(self, aid: str, task: str):
        def cb(goal) -> None:
            srv = [s for s in self.servers if s.action_server.ns == f"/{C.robot_ns(aid)}/{task}_action"][0]
            self.received.append((rospy.get_time(), aid, task))
            with self.lock:
                if aid in self.busy:
                    srv.set_aborted(text="busy")
                    return
                self.busy[aid] = task
            rospy.sleep(self.task_time)
            with self.lock:
                cmd = Command(aid, task, goal_dict(goal))
                ok, res = self.mission.apply(cmd)
                del self.busy[aid]
            result_type = getattr(cmsg, ACTION_TYPES[task] + "Result")
            result = result_type()
            for k, v in res.items():
                if hasattr(result, k):
                    setattr(result, k, v)
            if ok:
                srv.set_succeeded(result)
            else:
                srv.set_aborted(result)
        return cb

    def _publish(self, _event) -> None:
        now = rospy.Time.now()
        with self.lock:
            for aid, a in self.mission.agents.items():
                if aid in self.silent:
                    continue
                m = cmsg.AgentDataFeed()
                m.header.stamp = now
                m.agent_id = aid
                m.robot_type = a.robot_type
                m.payload = a.payload
                m.pose.header.frame_id = "arena"
                m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z = a.x, a.y, a.z
                m.pose.pose.orientation.w = 1.0
                m.ual_state = a.ual_state
                m.active_task = self.busy.get(aid, "")
                m.is_idle = aid not in self.busy
                m.battery = 1.0
                m.water_level = a.water_level
                m.has_blanket = a.has_blanket
                self.feeds[aid].publish(m)
            ol = cmsg.ObjectList(stamp=now)
            for f in self.mission.fires.values():
                o = cmsg.Object()
                o.header.stamp = now
                o.header.frame_id = "arena"
                o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = f.x, f.y, f.z
                o.pose.pose.orientation.w = 1.0
                o.type = C.TYPE_FIRE
                o.sub_type = {"facade": 1, "ground": 2, "indoor": 3}[f.kind]
                o.id = f.fire_id
                o.status = f.status
                ol.objects.append(o)
            self.objects.publish(ol)
