"""The ground station's picture of the trial, built from ROS messages: the one code path for live and replay.

`GroundStationState.apply(topic, msg, now)` folds one message into the cached state (`now` = sim time when it
arrived: live, the node's ROS time; in replay, the last /clock of the bag), and `frame(now)` returns the
plain-JSON picture the page draws. Neither imports ROS: messages are read by duck typing, and a malformed
message is counted and shown as unknown, never raised.
"""
from __future__ import annotations

import json
import math
from collections import deque
from typing import Any, Iterable, Optional

from mbzirc_arena.arena import floor_of
from mbzirc_arena.c3 import ARENA as DEFAULT_ARENA

from .constants import FIRE_KIND, FIRE_STATUS, GOAL_STATUS, LINK_LATE_S, STALE_AFTER, UAL_STATES, UGV_ID
from .routing import Route, route
from .summary import finite, point_of, summarise

__all__ = ["GroundStationState", "robot_name"]

TIME_JUMP_BACK_S = 1.0   # sim time going back more than this = a new trial (mission restarted)


def robot_name(robot: str) -> str:
    """'UGV' for id 0, else 'UAV <id>'."""
    return "UGV" if robot == UGV_ID else "UAV %s" % robot


def _yaw(q: Any) -> Optional[float]:
    x, y, z, w = (finite(getattr(q, a, None)) for a in "xyzw")
    if None in (x, y, z, w):
        return None
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _age(now: float, t: Optional[float]) -> Optional[float]:
    return None if t is None else round(max(0.0, now - t), 2)


def _freshness(now: float, t: Optional[float], kind: str) -> str:
    """'unknown' (never heard), 'stale' (older than STALE_AFTER[kind]) or 'ok'."""
    if t is None:
        return "unknown"
    return "stale" if now - t > STALE_AFTER[kind] else "ok"


class Track:
    """A robot's path on the map: a point every `step` metres, thinned to half when it exceeds `limit`."""

    def __init__(self, step: float, limit: int) -> None:
        self.step, self.limit = step, limit
        self.points: list[tuple[float, float]] = []

    def add(self, x: float, y: float) -> None:
        if self.points:
            lx, ly = self.points[-1]
            if math.hypot(x - lx, y - ly) < self.step:
                return
        self.points.append((round(x, 2), round(y, 2)))
        if len(self.points) > self.limit:
            self.points = self.points[::2] + ([self.points[-1]] if len(self.points) % 2 == 0 else [])


class RobotView:
    """What the ground station knows of one robot, with the sim time each part was last heard."""

    def __init__(self, robot: str, track: Track) -> None:
        self.id = robot
        self.kind = "ugv" if robot == UGV_ID else "uav"
        self.payload = ""
        self.pose: Optional[dict] = None
        self.feed_t: Optional[float] = None
        self.feed: dict = {}
        self.ual_state: Optional[int] = None
        self.water: Optional[float] = None
        self.blanket: Optional[bool] = None
        self.task: Optional[dict] = None
        self.smach: dict[str, list[str]] = {}
        self.smach_t: Optional[float] = None
        self.track = track

    def smach_state(self) -> Optional[str]:
        """Active state chain from the root container down ('search_facade/MOVING'), None when unknown."""
        if not self.smach:
            return None
        path = min(self.smach, key=lambda p: (p.count("/"), p))
        chain = []
        while path in self.smach and len(chain) < 8:
            active = self.smach[path]
            if not active:
                break
            chain.append(active[0])
            path = path + "/" + active[0]
        return "/".join(chain) if chain else "(idle)"

    def link(self, now: float) -> dict:
        age = _age(now, self.feed_t)
        if age is None:
            status = "unknown"
        elif age > STALE_AFTER["data_feed"]:
            status = "stale"
        else:
            status = "late" if age > LINK_LATE_S else "ok"
        return {"age": age, "status": status}

    def view(self, now: float, cu_agent: Optional[dict]) -> dict:
        feed_fresh = _freshness(now, self.feed_t, "data_feed")
        fresh = feed_fresh == "ok"
        ual = self.ual_state if fresh else None
        return {
            "id": self.id, "name": robot_name(self.id), "kind": self.kind, "payload": self.payload,
            "pose": self.pose, "pose_status": feed_fresh if self.pose else "unknown",
            "ual_state": UAL_STATES.get(ual, "unknown") if ual is not None else "unknown",
            "water": self.water if fresh else None, "blanket": self.blanket if fresh else None,
            "link": self.link(now),
            "agent": dict(self.feed) if fresh else None,
            "task": self.task,
            "smach": self.smach_state(), "smach_age": _age(now, self.smach_t),
            "cu": cu_agent,
        }


class GroundStationState:
    """Cached state of the whole trial; see the module docstring.

    Args:
        arena: the page's arena description (see arena.py), passed through to the page.
        robot_ids: robots expected (shown as unknown until heard from); others appear when heard.
        track_step, track_limit: track sampling (m) and the number of points kept per robot.
        log_limit: central-unit / operator log entries kept.
    """

    def __init__(self, arena: Optional[dict] = None, robot_ids: Iterable[str] = (), track_step: float = 0.5,
                 track_limit: int = 600, log_limit: int = 400) -> None:
        self.arena = arena
        self.track_step, self.track_limit = track_step, track_limit
        self.log_limit = log_limit
        self.expected = [str(r) for r in robot_ids]
        self.reset()

    def reset(self) -> None:
        """Forget everything heard (a new trial)."""
        self.now = 0.0
        self.robots: dict[str, RobotView] = {}
        for r in self.expected:
            self._robot(r)
        self.fires: list[dict] = []
        self.fires_t: Optional[float] = None
        self.regions: dict[str, dict] = {}
        self.regions_t: Optional[float] = None
        self.cu: Optional[dict] = None
        self.cu_t: Optional[float] = None
        self.cu_heartbeat_t: Optional[float] = None
        self.score: Optional[dict] = None
        self.score_t: Optional[float] = None
        self.log: deque = deque(maxlen=self.log_limit)
        self.log_seq = 0
        self.bad: dict[str, int] = {}
        self.messages = 0

    # ------------------------------------------------------------------ input
    def apply(self, topic: str, msg: Any, now: float) -> None:
        """Fold one message of `topic`, received at sim time `now`, into the state."""
        r = route(topic)
        if r is None:
            return
        now_f = finite(now)
        if now_f is None:
            return
        if now_f < self.now - TIME_JUMP_BACK_S:
            self.reset()
            self.add_log(now_f, "station", "sim time went back: a new trial, state cleared")
        self.now = max(self.now, now_f)
        self.messages += 1
        try:
            getattr(self, "_on_" + r.kind)(r, msg, now_f)
        except Exception as ex:  # noqa: BLE001 - bad input: counted and shown, never fatal
            self.bad[topic] = self.bad.get(topic, 0) + 1
            if self.bad[topic] in (1, 10, 100, 1000):
                self.add_log(now_f, "station", "malformed message on %s (%d so far): %s"
                             % (topic, self.bad[topic], type(ex).__name__))

    def add_log(self, t: float, source: str, text: str) -> None:
        self.log_seq += 1
        self.log.append({"seq": self.log_seq, "t": round(t, 1), "source": source, "text": text})

    def _robot(self, robot: str) -> RobotView:
        if robot not in self.robots:
            self.robots[robot] = RobotView(robot, Track(self.track_step, self.track_limit))
        return self.robots[robot]

    def _on_clock(self, r: Route, msg: Any, now: float) -> None:
        pass  # `now` already moved the state's clock

    def _on_data_feed(self, r: Route, msg: Any, now: float) -> None:
        rv = self._robot(r.robot)
        rv.feed_t = now
        rtype = str(msg.robot_type)
        if rtype in ("uav", "ugv"):
            rv.kind = rtype
        rv.payload = str(msg.payload)
        pose = msg.pose
        xyz = point_of(pose) if pose.header.frame_id else None   # empty frame: the agent has no pose yet
        yaw = _yaw(pose.pose.orientation) if xyz else None
        if xyz is None or yaw is None:
            rv.pose = None
        else:
            stamp = finite(pose.header.stamp.to_sec())   # when the robot was there (its UAL pose's time)
            rv.pose = {"x": round(xyz[0], 3), "y": round(xyz[1], 3), "z": round(xyz[2], 3), "yaw": round(yaw, 3),
                       "stamp": stamp}
            rv.track.add(xyz[0], xyz[1])
        rv.ual_state = int(msg.ual_state)
        water = finite(msg.water_level)
        rv.water = None if water is None else round(water, 2)
        rv.blanket = bool(msg.has_blanket)
        rv.feed = {"active_task": str(msg.active_task), "sub_state": str(msg.active_sub_state),
                   "idle": bool(msg.is_idle), "battery": finite(msg.battery)}

    def _on_smach(self, r: Route, msg: Any, now: float) -> None:
        rv = self._robot(r.robot)
        rv.smach[str(msg.path)] = [str(s) for s in msg.active_states]
        rv.smach_t = now

    def _on_action(self, r: Route, msg: Any, now: float) -> None:
        rv = self._robot(r.robot)
        who = robot_name(r.robot)
        if r.part == "goal":
            text = summarise(msg.goal)
            rv.task = {"name": r.task, "goal": text, "since": round(now, 1), "feedback": None, "result": None}
            self.add_log(now, "goal", "%s <- %s(%s)" % (who, r.task, text))
        elif r.part == "feedback":
            fb = msg.feedback
            if rv.task is None or rv.task["name"] != r.task:
                rv.task = {"name": r.task, "goal": None, "since": None, "feedback": None, "result": None}
            rv.task["feedback"] = {"state": str(getattr(fb, "state", "")), "message": str(getattr(fb, "message", "")),
                                   "t": round(now, 1)}
        else:
            status = GOAL_STATUS.get(int(msg.status.status), "?")
            message = str(getattr(msg.result, "message", ""))
            if rv.task is not None and rv.task["name"] == r.task:
                rv.task["result"] = {"status": status, "message": message, "t": round(now, 1)}
            self.add_log(now, "result", "%s %s: %s %s" % (who, r.task, status, message))

    def _on_fires(self, r: Route, msg: Any, now: float) -> None:
        fires = []
        for o in msg.objects:
            xyz = point_of(o.pose)
            floor = floor_of(xyz[2], self.floor_heights) if xyz else None
            kind = FIRE_KIND.get(int(o.sub_type), "unknown")
            if kind == "ground":
                floor = 0
            fires.append({"id": int(o.id), "kind": kind, "floor": floor,
                          "status": FIRE_STATUS.get(int(o.status), "unknown"),
                          "position": None if xyz is None else [round(v, 2) for v in xyz],
                          "updates": int(o.num_updates)})
        old = {f["id"]: f["status"] for f in self.fires}
        for f in fires:
            if old.get(f["id"]) != f["status"]:
                self.add_log(now, "estimator", "fire %d (%s, floor %s): %s"
                             % (f["id"], f["kind"], "?" if f["floor"] is None else f["floor"], f["status"]))
        self.fires, self.fires_t = fires, now

    @property
    def floor_heights(self) -> list:
        """The floors of the arena drawn (the default C3 arena's when none is)."""
        return (self.arena or {}).get("floors") or list(DEFAULT_ARENA.floor_heights)

    def _on_regions(self, r: Route, msg: Any, now: float) -> None:
        for m in msg.markers:
            action = int(m.action)
            if action == 3:          # DELETEALL
                self.regions = {}
                continue
            key = "%s#%d" % (m.ns, int(m.id))
            if action == 2:          # DELETE
                self.regions.pop(key, None)
                continue
            c = point_of(m.pose)
            sx, sy, sz = (finite(getattr(m.scale, a, None)) for a in "xyz")
            if c is None or None in (sx, sy, sz):
                continue
            agent, _, label = str(m.ns).partition("/")
            self.regions[key] = {"agent": agent, "label": label,
                                 "rect": [round(c[0] - sx / 2, 2), round(c[1] - sy / 2, 2),
                                          round(c[0] + sx / 2, 2), round(c[1] + sy / 2, 2)],
                                 "z": [round(c[2] - sz / 2, 2), round(c[2] + sz / 2, 2)]}
        self.regions_t = now

    def _on_cu_status(self, r: Route, msg: Any, now: float) -> None:
        status = json.loads(str(msg.data))
        if not isinstance(status, dict) or not isinstance(status.get("agents", {}), dict):
            raise ValueError("central unit status is not a JSON object")
        self._log_decisions(self.cu, status, now)
        self.cu, self.cu_t = status, now
        for aid in status.get("agents", {}):
            if str(aid).isdigit():
                self._robot(str(aid))   # a robot the central unit knows is shown even before its agent speaks

    def _log_decisions(self, old: Optional[dict], new: dict, now: float) -> None:
        """A log line per agent whose task or activity changed, and per change of floor owner."""
        old_agents = (old or {}).get("agents", {}) or {}
        for aid, a in sorted(new.get("agents", {}).items()):
            if not isinstance(a, dict):
                continue
            before = old_agents.get(aid) if isinstance(old_agents.get(aid), dict) else {}
            if (a.get("task"), a.get("doing")) != (before.get("task"), before.get("doing")):
                self.add_log(now, "central unit", "%s: %s%s" % (robot_name(str(aid)), a.get("task") or "idle",
                                                                 (" - %s" % a["doing"]) if a.get("doing") else ""))
            if a.get("alive") is False and before.get("alive") is not False:
                self.add_log(now, "central unit", "%s: silent (work reassigned)" % robot_name(str(aid)))
        for key in ("floor_owner", "indoor_owner"):
            if (new.get(key) or {}) != ((old or {}).get(key) or {}):
                self.add_log(now, "central unit", "%s: %s" % (key.replace("_", " "), json.dumps(new.get(key))))
        if new.get("paused") != (old or {}).get("paused") and "paused" in new:
            self.add_log(now, "central unit", "paused" if new["paused"] else "running")

    def _on_cu_heartbeat(self, r: Route, msg: Any, now: float) -> None:
        self.cu_heartbeat_t = now

    def _on_score(self, r: Route, msg: Any, now: float) -> None:
        self.score = {"score": finite(msg.score), "max_score": finite(msg.max_score),
                      "fires_extinguished": int(msg.fires_extinguished), "elapsed": finite(msg.elapsed),
                      "time_left": finite(msg.time_left), "crashed": [str(c) for c in msg.crashed_robots]}
        self.score_t = now

    # ------------------------------------------------------------------ output
    def frame(self, now: Optional[float] = None, tracks: bool = False, log_tail: int = 60) -> dict:
        """The page's picture at sim time `now` (default: the last message's time)."""
        now = self.now if now is None else now
        cu_agents = (self.cu or {}).get("agents", {}) if _freshness(now, self.cu_t, "cu_status") == "ok" else {}
        robots = [self.robots[k].view(now, cu_agents.get(k) if isinstance(cu_agents, dict) else None)
                  for k in sorted(self.robots, key=lambda s: (len(s), s))]
        cu_fresh = _freshness(now, self.cu_t, "cu_status")
        out = {
            "t": round(now, 2),
            "robots": robots,
            "fires": self.fires, "fires_status": _freshness(now, self.fires_t, "fires"),
            "regions": list(self.regions.values()), "regions_status": _freshness(now, self.regions_t, "regions"),
            "cu": {"status": cu_fresh, "age": _age(now, self.cu_t),
                   "heartbeat": _freshness(now, self.cu_heartbeat_t, "cu_heartbeat"),
                   "heartbeat_age": _age(now, self.cu_heartbeat_t),
                   "paused": (self.cu or {}).get("paused"), "started": (self.cu or {}).get("started"),
                   "floor_owner": (self.cu or {}).get("floor_owner"),
                   "indoor_owner": (self.cu or {}).get("indoor_owner")},
            "log": list(self.log)[-log_tail:],
            "ground_truth": (dict(self.score, age=_age(now, self.score_t))
                             if self.score and _freshness(now, self.score_t, "score") == "ok" else None),
            "bad_messages": dict(self.bad),
        }
        if tracks:
            out["tracks"] = {k: rv.track.points for k, rv in self.robots.items()}
        return out
