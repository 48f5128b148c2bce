"""ROS adapter of the strategy: data_feeds and /estimated_objects in, action goals out, heartbeat, status.

The node holds no mission state of its own beyond the goals it has in flight: every tick it rebuilds the
`WorldView` from the latest messages and asks `Strategy.decide` what idle agents do next. A restarted node
therefore resumes from the agents' data_feeds and the estimator's tracks.
"""
from __future__ import annotations

import json
import math
import threading
from typing import Any

import actionlib
import rospy
import yaml
from actionlib_msgs.msg import GoalStatus
from geometry_msgs.msg import PoseStamped
from mbzirc_comm_objs import msg as cmsg
from mbzirc_arena.messages import feed_position
from mbzirc_comm_objs.srv import FreeRegions
from mbzirc_ros_utils.liveness import new_run_id
from mbzirc_ros_utils.periodic import PeriodicTimer
from std_msgs.msg import Header, String

from . import constants as C
from .goal_timeouts import GoalClock
from .layout import INDOOR_SEARCHES, Layout, explored_layout, load_world
from .operator import OperatorGate
from .strategy import Command, Strategy, StrategyParams
from .world_model import AgentView, FireView, WorldView, facade_floor, fire_kind

ACTION_TYPES = {
    C.TAKE_OFF: "TakeOff", C.LAND: "Land", C.GO_TO: "GoTo", C.FOLLOW_PATH: "FollowPath", C.HOVER: "Hover",
    C.SEARCH_FACADE: "SearchFacade", C.GO_TO_FACADE_FIRE: "GoToFacadeFire",
    C.EXTINGUISH_FACADE_FIRE: "ExtinguishFacadeFire", C.LOOK_FOR_GROUND_FIRES: "LookForGroundFires",
    C.EXTINGUISH_GROUND_FIRE: "ExtinguishGroundFire", C.ENTER_BUILDING: "EnterBuilding",
    C.SEARCH_INDOOR: "SearchIndoor", C.EXTINGUISH_INDOOR_FIRE: "ExtinguishIndoorFire",
    C.GO_HOME_AND_REFILL: "GoHomeAndRefill",
}
FRAME = "arena"


def _finite(*vals: float) -> bool:
    return all(isinstance(v, (int, float)) and math.isfinite(v) for v in vals)


def pose_msg(p: tuple, stamp: rospy.Time) -> PoseStamped:
    """(x, y, z, yaw) -> PoseStamped in the arena frame; yaw None: the all-zero quaternion (no heading: the
    agents look around there, and with ~indoor_search explore explore the floor from there)."""
    m = PoseStamped()
    m.header.frame_id = FRAME
    m.header.stamp = stamp
    m.pose.position.x, m.pose.position.y, m.pose.position.z = float(p[0]), float(p[1]), float(p[2])
    if len(p) > 3 and p[3] is None:
        return m
    yaw = float(p[3]) if len(p) > 3 else 0.0
    m.pose.orientation.z, m.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return m


def goal_msg(cmd: Command, stamp: rospy.Time) -> Any:
    """Action goal of a command: tuples become PoseStamped, lists of tuples PoseStamped[]."""
    goal = getattr(cmsg, ACTION_TYPES[cmd.task] + "Goal")()
    for key, val in cmd.goal.items():
        if key.startswith("_"):
            continue
        if isinstance(val, list):
            val = [pose_msg(p, stamp) for p in val]
        elif isinstance(val, tuple):
            val = pose_msg(val, stamp)
        setattr(goal, key, val)
    return goal


def result_dict(result: Any) -> dict[str, Any]:
    """The fields of an action result we use, whatever the action type."""
    if result is None:
        return {}
    out = {}
    for k in ("message", "extinguished", "water_left", "water_level", "has_blanket"):
        if hasattr(result, k):
            out[k] = getattr(result, k)
    if hasattr(result, "fire_ids"):
        out["fire_ids"] = list(result.fire_ids)
    return out


class CentralUnit:
    """Action client of every agent, running the Challenge 3 strategy.

    Args (all `~` params): see the package README.
    """

    def __init__(self) -> None:
        self.agent_ids = self._agent_ids()
        params = StrategyParams(
            agent_timeout=float(rospy.get_param("~agent_timeout", C.AGENT_TIMEOUT)),
            floor_priority=[int(f) for f in rospy.get_param("~floor_priority", list(C.FLOOR_PRIORITY))],
            indoor_floors=[int(f) for f in rospy.get_param("~indoor_floors", list(C.INDOOR_FLOORS))],
            altitudes={str(k): float(v) for k, v in
                       rospy.get_param("~altitudes", dict(C.DEFAULT_ALTITUDES)).items()},
            layout=self._layout(str(rospy.get_param("~world_file", "")), self._indoor_search()),
            fire_distance=float(rospy.get_param("~fire_distance", C.FIRE_DISTANCE)),
            min_water=float(rospy.get_param("~min_water", C.MIN_WATER)),
            num_ground_fires=int(rospy.get_param("~num_ground_fires", 2)),
            facade_searches=int(rospy.get_param("~searches", 2)),
            second_search_first=bool(rospy.get_param("~second_search_first", True)),
            max_failures=int(rospy.get_param("~max_failures", C.MAX_TASK_FAILURES)),
            leg_blocked_backoff=float(rospy.get_param("~leg_blocked_backoff", C.LEG_BLOCKED_BACKOFF)),
            leg_blocked_backoff_max=float(rospy.get_param("~leg_blocked_backoff_max", C.LEG_BLOCKED_BACKOFF_MAX)),
            max_blocked_legs=int(rospy.get_param("~max_blocked_legs", C.MAX_BLOCKED_LEGS)),
            not_seen_hot_limit=int(rospy.get_param("~not_seen_hot_limit", C.NOT_SEEN_HOT_LIMIT)),
            facade_top_up_limit=int(rospy.get_param("~facade_top_up_limit", C.FACADE_TOP_UP_LIMIT)),
            uavs_take_ground_floor_indoors=bool(rospy.get_param("~uavs_take_ground_floor_indoors", False)),
        )
        self.strategy = Strategy(params)
        self.facade_holders = params.layout.facade_holders
        self.operator = OperatorGate(bool(rospy.get_param("~wait_for_start", False)))   # operator.py
        self.operator_services = self.operator.advertise()
        self.lock = threading.Lock()
        self.agents: dict[str, AgentView] = {}
        self.fires: dict[int, FireView] = {}
        self.clients: dict[tuple[str, str], actionlib.SimpleActionClient] = {}
        self.results: list[tuple[Command, int, dict]] = []
        self.feedback: dict[str, str] = {}
        self.silent: set[str] = set()
        self.freed: set[str] = set()  # crashed agents whose reserved regions were freed
        self.goal_clock = GoalClock(float(rospy.get_param("~task_timeout_scale", 1.0)))   # goal_timeouts.py
        self.heartbeat_pub = rospy.Publisher("/central_unit/heartbeat", Header, queue_size=1)
        self.status_pub = rospy.Publisher("/central_unit/status", String, queue_size=1, latch=True)
        self.subs = [rospy.Subscriber(f"/{C.robot_ns(i)}/data_feed", cmsg.AgentDataFeed, self._on_feed,
                                      callback_args=i, queue_size=1) for i in self.agent_ids]
        self.subs.append(rospy.Subscriber("/estimated_objects", cmsg.ObjectList, self._on_objects, queue_size=1))
        self.seq = 0
        # the heartbeat names this run (mission = the master's /run_id, a new instance per start) and is sent
        # by the tick itself, after each completed step: it proves that decisions are being made, not only
        # that the process runs (a timer beside the tick kept beating while the tick was blocked)
        self.run_id = new_run_id("central_unit", str(rospy.get_param("/run_id", "") or ""))
        self.hb_period = 1.0 / float(rospy.get_param("~heartbeat_rate", 2.0))   # at most this often
        self._last_hb = -1e9
        # not rospy.Timer: its thread dies when /clock goes back (mbzirc_ros_utils.periodic)
        self.tick_timer = PeriodicTimer(1.0 / float(rospy.get_param("~rate", 2.0)), self._tick, "central unit tick")
        rospy.on_shutdown(self._shutdown)
        rospy.loginfo("central_unit: agents %s, layout with %d facade holders, %d rooms",
                      self.agent_ids, len(params.layout.facade_holders),
                      sum(len(r) for r in params.layout.rooms.values()))

    # ---- params ----------------------------------------------------------------------------------
    @staticmethod
    def _agent_ids() -> list[str]:
        ids = rospy.get_param("~agents", None)
        if ids:
            return [str(i) for i in ids]
        uavs = int(rospy.get_param("~uavs", 3))
        out = [str(i) for i in range(1, uavs + 1)]
        if bool(rospy.get_param("~ugv", True)):
            out.insert(0, C.UGV_ID)
        return out

    @staticmethod
    def _indoor_search() -> str:
        """`~indoor_search`: explore (rooms = the windows: what a team knows) or plan (the first wave's plan
        read from the simulator's interior walls and indoor holders: a test aid)."""
        mode = str(rospy.get_param("~indoor_search", "explore"))
        if mode not in INDOOR_SEARCHES:
            rospy.logerr("central_unit: ~indoor_search %r is not one of %s: using 'explore'", mode, INDOOR_SEARCHES)
            return "explore"
        return mode

    @staticmethod
    def _layout(path: str, indoor_search: str = "plan") -> Layout:
        default = explored_layout if indoor_search == "explore" else Layout
        if not path:
            return default()
        try:
            with open(path, encoding="utf-8") as f:
                return load_world(yaml.safe_load(f), indoor_search)
        except (OSError, yaml.YAMLError, KeyError, TypeError, ValueError) as e:
            rospy.logerr("central_unit: cannot read world file %s (%s): using the default layout", path, e)
            return default()

    # ---- inputs ----------------------------------------------------------------------------------
    def _on_feed(self, msg: cmsg.AgentDataFeed, agent_id: str) -> None:
        xyz = feed_position(msg)
        now = rospy.get_time()
        with self.lock:
            a = self.agents.get(agent_id) or AgentView(agent_id, reported=False)
            a.last_seen = now
            if xyz is not None:
                a.x, a.y, a.z = xyz
            elif msg.pose.header.frame_id:
                rospy.logerr_throttle(5.0, f"central_unit: data_feed of {agent_id} has a non-finite pose: ignored")
            a.robot_type = msg.robot_type or (C.ROBOT_UGV if agent_id == C.UGV_ID else C.ROBOT_UAV)
            a.payload = msg.payload or a.payload
            a.ual_state = msg.ual_state
            a.active_task = msg.active_task
            a.active_sub_state = msg.active_sub_state
            a.is_idle = msg.is_idle
            a.battery = msg.battery if _finite(msg.battery) else a.battery
            a.water_level = msg.water_level if _finite(msg.water_level) else 0.0
            a.has_blanket = msg.has_blanket
            a.reported = a.reported or xyz is not None
            self.agents[agent_id] = a

    def _on_objects(self, msg: cmsg.ObjectList) -> None:
        fires: dict[int, FireView] = {}
        for o in msg.objects:
            if o.type != C.TYPE_FIRE:
                continue
            p = o.pose.pose.position
            if not _finite(p.x, p.y, p.z):
                rospy.logerr_throttle(5.0, f"central_unit: estimated object {o.id} has a non-finite pose: ignored")
                continue
            kind = fire_kind(o.sub_type, p.x, p.y, p.z)
            storey = facade_floor((p.x, p.y, p.z), self.facade_holders) if kind == C.KIND_FACADE else None
            fires[o.id] = FireView(o.id, p.x, p.y, p.z, kind, o.status, holder_floor=storey)
        with self.lock:
            self.fires = fires

    # ---- outputs ---------------------------------------------------------------------------------
    def _heartbeat(self) -> None:
        now = rospy.get_time()
        if self._last_hb <= now < self._last_hb + self.hb_period:
            return                 # ticks faster than ~heartbeat_rate: not every tick
        # the next one is due a period after this one was due (not after now): ~heartbeat_rate on average
        # whatever the tick's phase; a late or time-jumped tick restarts the schedule
        due = self._last_hb + self.hb_period
        self._last_hb = due if 0.0 <= now - due < self.hb_period else now
        self.seq += 1
        h = Header(seq=self.seq, stamp=rospy.Time.now(), frame_id=self.run_id)
        self.heartbeat_pub.publish(h)

    def _client(self, agent_id: str, task: str) -> actionlib.SimpleActionClient:
        key = (agent_id, task)
        if key not in self.clients:
            action = getattr(cmsg, ACTION_TYPES[task] + "Action")
            self.clients[key] = actionlib.SimpleActionClient(f"/{C.robot_ns(agent_id)}/{task}_action", action)
        return self.clients[key]

    def _send(self, cmd: Command) -> None:
        client = self._client(cmd.agent_id, cmd.task)
        if not client.wait_for_server(rospy.Duration(0.05)):
            rospy.logwarn_throttle(10.0, f"central_unit: {cmd.agent_id}/{cmd.task}_action not available yet")
            self.strategy.forget(cmd)
            return
        goal = goal_msg(cmd, rospy.Time.now())

        def done(status: int, result: Any, cmd: Command = cmd) -> None:
            with self.lock:
                self.results.append((cmd, status, result_dict(result)))

        def feedback(fb: Any, agent_id: str = cmd.agent_id) -> None:
            self.feedback[agent_id] = getattr(fb, "message", "") or getattr(fb, "state", "")

        client.send_goal(goal, done_cb=done, feedback_cb=feedback)
        self.goal_clock.started(cmd, rospy.get_time())
        rospy.loginfo(f"central_unit: {cmd.agent_id} <- {cmd.describe()}")

    def _free_regions_of(self, agent_id: str) -> None:
        """A crashed robot lies where it fell and will never free its reserved boxes: free them, or the
        other UAVs wait for them forever."""
        try:
            rospy.wait_for_service("/free_regions", timeout=0.2)
            rospy.ServiceProxy("/free_regions", FreeRegions)(agent_id=agent_id, label="", free_all=True)
            rospy.logwarn(f"central_unit: agent {agent_id} crashed: its work is reassigned, its regions freed")
            self.freed.add(agent_id)
        except (rospy.ROSException, rospy.ServiceException) as e:
            rospy.logerr_throttle(10.0, f"central_unit: cannot free the regions of crashed {agent_id}: {e}")

    # ---- the loop --------------------------------------------------------------------------------
    def _tick(self, _event: Any) -> None:
        try:
            self._step()
        except Exception as e:  # noqa: BLE001 - the mission must go on; say what broke
            rospy.logerr_throttle(5.0, f"central_unit: tick failed: {type(e).__name__}: {e}")
            return                 # no heartbeat for a step that did not complete
        self._heartbeat()

    def _step(self) -> None:
        now = rospy.get_time()
        with self.lock:
            results, self.results = self.results, []
            world = WorldView(now, {k: AgentView(**vars(v)) for k, v in self.agents.items()}, dict(self.fires))
        for cmd, status, res in results:
            if self.strategy.in_flight.get(cmd.agent_id) is not cmd:
                continue  # a goal we gave up (silent agent)
            ok = status == GoalStatus.SUCCEEDED
            msg = str(res.get("message", ""))
            # Not the task's fault: the agent was busy, or refused goals (e.g. until it hears our heartbeat
            # again after a restart). Try again later without counting a failure.
            not_tried = status == GoalStatus.REJECTED or msg.startswith("busy") or "heartbeat" in msg
            if not_tried:
                self.strategy.forget(cmd)
            else:
                self.strategy.on_result(cmd, ok, res, now)
            level = rospy.loginfo if ok else rospy.logwarn
            level(f"central_unit: {cmd.agent_id} {cmd.task} -> {GoalStatus.to_string(status)} "
                  f"{res.get('message', '')}")
        for cmd, waited in self.goal_clock.overdue(self.strategy.in_flight, now):
            # no result in the task's bound (goal_timeouts.py): a zombie agent, a lost result, a stuck call
            rospy.logwarn(f"central_unit: {cmd.agent_id} {cmd.task} gave no result in {waited:.0f} s: "
                          "cancelled, counted as a failure")
            self._client(cmd.agent_id, cmd.task).cancel_goal()
            self.strategy.on_result(cmd, False, {"message": f"timed out after {waited:.0f} s"}, now)
        for note in self.strategy.take_notes():
            rospy.logwarn(f"central_unit: {note}")   # failure_rules.py: blocked legs, fires probably out
        for agent_id in self.agent_ids:
            a = world.agents.get(agent_id)
            alive = a is not None and a.alive(now, self.strategy.p.agent_timeout)
            if not alive and agent_id not in self.silent and a is not None:
                rospy.logwarn(f"central_unit: agent {agent_id} silent: its work is reassigned")
                self.silent.add(agent_id)
                cmd = self.strategy.in_flight.get(agent_id)
                if cmd is not None:
                    self._client(agent_id, cmd.task).cancel_goal()
                self.strategy.on_silent(agent_id)
            elif alive and agent_id in self.silent:
                rospy.loginfo(f"central_unit: agent {agent_id} is back")
                self.silent.discard(agent_id)
        for cmd in self.strategy.decide(world) if self.operator.deciding() else []:
            self._send(cmd)
        for agent_id in sorted(self.strategy.crashed - self.freed):
            self._free_regions_of(agent_id)
        self._publish_status(world)

    def _publish_status(self, world: WorldView) -> None:
        agents = {}
        for i in self.agent_ids:
            a = world.agents.get(i)
            cmd = self.strategy.in_flight.get(i)
            agents[i] = {
                "alive": bool(a and a.alive(world.now, self.strategy.p.agent_timeout)),
                "task": cmd.task if cmd else (a.active_task if a else ""),
                "doing": (cmd.reason if cmd else "idle"),
                "feedback": self.feedback.get(i, ""),
                "water": round(a.water_level, 2) if a else 0.0,
                "kind": a.robot_type if a else "",
                "payload": a.payload if a else "",
                "pos": [round(v, 1) for v in a.position] if a else None,
            }
        fires = [{"id": f.fire_id, "kind": f.kind, "floor": f.floor, "status": f.status,
                  "probably_out": self.strategy.probably_out(f.fire_id)} for f in world.fires.values()]
        self.status_pub.publish(String(json.dumps({"t": round(world.now, 1), "agents": agents, "fires": fires,
                                                   "floor_owner": self.strategy.floor_owner,
                                                   "indoor_owner": self.strategy.indoor_owner,
                                                   **self.operator.status()})))

    def _shutdown(self) -> None:
        self.tick_timer.shutdown()
        for cmd in list(self.strategy.in_flight.values()):
            try:
                self._client(cmd.agent_id, cmd.task).cancel_goal()
            except Exception:  # noqa: BLE001 - shutting down anyway
                pass
