"""Runs a mission distributed over network-namespace hosts and injects the scheduled faults.

Why: the only convincing proof that the system survives Wi-Fi drops and crashes is to run the real
launch files, one host per robot plus the ground station, cut links and kill -9 nodes mid-mission, and
look at what the central unit and the referee (mission recorder) report.

How: the lab (``netns.NetnsLab``) is built first; then this process moves its own network stack into the
ground-station namespace (``setns``) so that its monitor node reaches every host, like a tool running on
the ground station. Links are cut with ``ip`` (named namespaces are reachable from anywhere) and nodes are
killed by pid (namespaces share the PID space).
"""
from __future__ import annotations

import ctypes
import glob
from datetime import datetime, timedelta
import json
import os
import shutil
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Optional

from mbzirc_robustness import constants as C
from mbzirc_robustness import faults as F
from mbzirc_robustness.netns import NetnsLab, install_signal_cleanup, wait_tcp

CLONE_NEWNET = 0x40000000


def enter_namespace(ns: str) -> None:
    """Move the calling thread (and every thread it creates later) into named network namespace ``ns``."""
    libc = ctypes.CDLL(None, use_errno=True)
    fd = os.open(f"/run/netns/{ns}", os.O_RDONLY)
    try:
        if libc.setns(fd, CLONE_NEWNET) != 0:
            err = ctypes.get_errno()
            raise OSError(err, f"setns({ns}) failed: {os.strerror(err)}")
    finally:
        os.close(fd)


@dataclass
class SuiteConfig:
    """What to run. Times in sim seconds unless named ``*_wall_s``."""

    uavs: int = 3
    ugv: bool = True
    seed: int = 1
    rtf: float = 4.0
    duration: float = 600.0
    link_cut_s: float = C.LINK_CUT_S
    start_s: float = 40.0
    spacing_s: float = 25.0
    # wall seconds a killed node has to come back: a Python node's start (imports, init_node, first
    # connections) took 15-45 s under the load average of 50-70 this machine has during make test
    recover_wall_s: float = 90.0
    startup_wall_s: float = 180.0
    # stop the mission as soon as every fault is judged (and a permanently cut UAV had the time to decide
    # to go home) instead of at ``duration``: the short run of ``make test``
    stop_when_done: bool = False
    # the agents' heartbeat timeouts (mbzirc_agents defaults, wall clock): what the cut agents' logs are judged by
    agent_timeout_wall_s: float = 5.0
    return_home_wall_s: float = 60.0
    out_dir: str = "results/robustness/faults"
    fuzz_dir: str = "results/robustness"  # every fuzz_report*.json there is merged into the report
    report_path: str = "results/robustness/report.json"
    schedule: list[F.Fault] = field(default_factory=list)


class Monitor:
    """The fault suite's eyes on the ground station: central-unit status, heartbeats, data feeds, tracks,
    reserved regions; and its hand on ``/clock`` (the clock faults)."""

    # the periodic outputs of the system a clock fault must not silence (plus every robot's data_feed)
    OUTPUTS = ("/central_unit/heartbeat", "/central_unit/status", "/estimated_objects")

    def __init__(self) -> None:
        import rospy
        from mbzirc_comm_objs.msg import AgentDataFeed, ObjectList
        from rosgraph_msgs.msg import Clock
        from std_msgs.msg import Header, String
        from visualization_msgs.msg import MarkerArray
        self.rospy = rospy
        self.lock = threading.Lock()
        self.history: list[tuple[float, dict[str, Any]]] = []
        self.out_of_order_statuses = 0
        self.last_heartbeat_wall = 0.0
        self.last_feed_wall: dict[str, float] = {}
        self.last_seen: dict[str, float] = {}      # output topic -> monotonic time of its last message
        self.last_tracks: Optional[int] = None
        self.last_tracks_wall = 0.0
        self.last_objects: dict[int, int] = {}     # id -> status of the last /estimated_objects
        self.objects_log: deque[tuple[float, dict[int, int]]] = deque(maxlen=600)  # (wall, id -> status)
        self.objects_walls: deque[float] = deque(maxlen=5000)
        # (wall, {agent/label}, table number shown or None)
        self.regions_log: deque[tuple[float, frozenset, Optional[int]]] = deque(maxlen=120)
        self.feeds: dict[str, deque] = {}          # robot -> (wall, active_sub_state) of its data_feeds
        self.clock_pub = rospy.Publisher("/clock", Clock, queue_size=100)         # clock faults only
        self.subs = [rospy.Subscriber("/central_unit/status", String, self._on_status, queue_size=10),
                     rospy.Subscriber("/central_unit/heartbeat", Header, self._on_heartbeat, queue_size=1),
                     rospy.Subscriber("/estimated_objects", ObjectList, self._on_objects, queue_size=1),
                     rospy.Subscriber("/regions", MarkerArray, self._on_regions, queue_size=1)]
        for i in range(0, 10):
            self.subs.append(rospy.Subscriber(f"/mbzirc2020_{i}/data_feed", AgentDataFeed, self._on_feed,
                                              callback_args=str(i), queue_size=1))

    def _seen(self, topic: str) -> float:
        now = time.monotonic()
        self.last_seen[topic] = now
        return now

    def _on_status(self, msg) -> None:
        self._seen("/central_unit/status")
        try:
            st = json.loads(msg.data)
        except ValueError:
            return
        with self.lock:
            t = float(st.get("t", self.rospy.get_time()))
            if self.history and t < self.history[-1][0] - 5.0:
                # published during a clock fault (sim time back for a moment): not a point of the mission's
                # timeline, where it would look like a status from before the earlier faults
                self.out_of_order_statuses += 1
                return
            self.history.append((t, st))

    def _on_heartbeat(self, _msg) -> None:
        self.last_heartbeat_wall = self._seen("/central_unit/heartbeat")

    def _on_feed(self, msg, robot: str) -> None:
        now = self._seen(f"/mbzirc2020_{robot}/data_feed")
        self.last_feed_wall[robot] = now
        with self.lock:
            self.feeds.setdefault(robot, deque(maxlen=2000)).append((now, str(msg.active_sub_state)))

    def feeds_since(self, robot: str, wall: float) -> list[tuple[float, str]]:
        """(wall s after ``wall``, active_sub_state) of the robot's data_feeds since then."""
        with self.lock:
            return [(t - wall, st) for t, st in self.feeds.get(robot, ()) if t >= wall]

    def _on_objects(self, msg) -> None:
        objs = {int(o.id): int(o.status) for o in msg.objects}
        now = self._seen("/estimated_objects")
        with self.lock:
            self.last_objects = objs
            self.objects_log.append((now, objs))
            self.objects_walls.append(now)
        self.last_tracks = len(msg.objects)
        self.last_tracks_wall = now

    def _on_regions(self, msg) -> None:
        names = frozenset(m.ns for m in msg.markers if m.ns and m.action == m.ADD)
        table = next((F.shown_table(m.text) for m in msg.markers if m.action == m.DELETEALL), None)
        with self.lock:
            self.regions_log.append((self._seen("/regions"), names, table))

    def first_objects_after(self, wall: float) -> Optional[dict[int, int]]:
        """The first /estimated_objects received after monotonic time ``wall`` (None if none yet)."""
        with self.lock:
            return next((o for t, o in self.objects_log if t > wall), None)

    def regions_before(self, wall: float) -> Optional[tuple[frozenset, Optional[int]]]:
        """(reservations, table number) of the last /regions received before ``wall``."""
        with self.lock:
            return next(((r, n) for t, r, n in reversed(self.regions_log) if t <= wall), None)

    def regions_after(self, wall: float) -> Optional[tuple[frozenset, Optional[int]]]:
        with self.lock:
            return next(((r, n) for t, r, n in self.regions_log if t > wall), None)

    def objects_gaps(self, start: float, end: float) -> list[float]:
        """Pauses (wall s) between /estimated_objects messages within [start, end], edges included."""
        with self.lock:
            times = [t for t in self.objects_walls if start <= t <= end]
        pts = [start] + times + [end]
        return [b - a for a, b in zip(pts, pts[1:])] if times else []

    def flowing(self, since: float) -> list[str]:
        """Outputs published since monotonic time ``since``."""
        return sorted(t for t, w in self.last_seen.items() if w >= since and t != "/regions")

    def sim_time(self) -> float:
        return self.rospy.get_time()


class FaultSuite:
    """Builds the lab, starts the mission on it, runs ``cfg.schedule`` and writes the robustness report."""

    def __init__(self, cfg: SuiteConfig) -> None:
        self.cfg = cfg
        self.cfg.schedule = cfg.schedule or F.default_schedule(cfg.uavs, cfg.link_cut_s, cfg.start_s, cfg.spacing_s,
                                                               ugv=cfg.ugv)
        self.log: list[str] = []
        self.lab: Optional[NetnsLab] = None
        self.cut_robots: set[str] = set()
        self.recovering: set[str] = set()          # nodes killed whose recovery is being watched
        self.kill_walls: dict[str, float] = {}     # node -> monotonic time of its kill -9

    def say(self, text: str) -> None:
        """One line of progress, wall-clock stamped (printed and kept for the report)."""
        line = f"[faults] {datetime.now():%H:%M:%S} {text}"
        print(line, flush=True)
        self.log.append(line)

    # ---- lab and mission ------------------------------------------------------------------------
    def _robot_hosts(self) -> list[tuple[str, str, list[str]]]:
        """(host, robot id, roslaunch args) of every robot."""
        out = []
        if self.cfg.ugv:
            out.append(("ugv", "0", ["mbzirc_launchers", "ugv.launch", "id:=0"]))
        for i in range(1, self.cfg.uavs + 1):
            payload = "blanket" if i == 1 else "water"
            out.append((f"uav{i}", str(i), ["mbzirc_launchers", "uav.launch", f"id:={i}", f"payload:={payload}"]))
        return out

    def _env(self, host: str) -> dict[str, str]:
        env = self.lab.env_for(host)
        env["ROS_LOG_DIR"] = os.path.join(self.out, "logs", host)
        return env

    def _start(self) -> None:
        lab = self.lab
        gs = lab.add_host(C.GROUND_STATION)
        for host, _rid, _args in self._robot_hosts():
            lab.add_host(host)
        self.say("hosts: " + ", ".join(f"{h.name}={h.ip}" for h in lab.hosts.values()))
        summary = os.path.join(self.out, "summary.json")
        lab.popen(C.GROUND_STATION, ["roslaunch", "-p", str(C.MASTER_PORT), "mbzirc_robustness",
                                     "ground_station_faults.launch", f"uavs:={self.cfg.uavs}",
                                     f"ugv:={str(self.cfg.ugv).lower()}", f"seed:={self.cfg.seed}",
                                     f"rtf:={self.cfg.rtf}", f"duration:={self.cfg.duration}",
                                     f"output_dir:={self.out}", f"summary_path:={summary}"],
                  env=self._env(C.GROUND_STATION), log_path=os.path.join(self.out, "gs.log"))
        self.gs_proc = lab.hosts[C.GROUND_STATION].procs[-1]
        first_robot = self._robot_hosts()[0][0]
        if not wait_tcp(lab, first_robot, gs.ip, C.MASTER_PORT, timeout=60):
            raise RuntimeError("the master on the ground station never came up (see gs.log)")
        for host, _rid, args in self._robot_hosts():
            lab.popen(host, ["roslaunch", "--wait", *args], env=self._env(host),
                      log_path=os.path.join(self.out, f"{host}.log"))
        # this process becomes a tool on the ground station
        enter_namespace(gs.ns)
        os.environ.update(self._env(C.GROUND_STATION))
        os.environ.pop("ROS_HOSTNAME", None)

    def _wait_mission(self, mon: Monitor) -> float:
        """Sim time at which every robot is reported alive by the central unit (mission under way)."""
        deadline = time.monotonic() + self.cfg.startup_wall_s
        ids = [rid for _h, rid, _a in self._robot_hosts()]
        while time.monotonic() < deadline and self.gs_proc.poll() is None:
            with mon.lock:
                last = mon.history[-1][1] if mon.history else None
            if last and all((last.get("agents") or {}).get(r, {}).get("alive") for r in ids):
                return mon.sim_time()
            time.sleep(1.0)
        raise RuntimeError("the mission never started: not every robot was alive in /central_unit/status "
                           f"within {self.cfg.startup_wall_s:.0f} s (see {self.out}/*.log)")

    # ---- faults --------------------------------------------------------------------------------
    def _pid(self, node: str) -> Optional[int]:
        import rosgraph
        from mbzirc_robustness.graph import query_pid
        return query_pid(rosgraph.Master("/robustness_faults"), node, "/robustness_faults", timeout=2.0)

    def _bus_info(self, node: str) -> list:
        import rosgraph
        from mbzirc_robustness.graph import query_bus_info
        return query_bus_info(rosgraph.Master("/robustness_faults"), node, "/robustness_faults", timeout=2.0)

    def _bus_inputs(self, node: str) -> set[str]:
        return F.connected_inputs(self._bus_info(node))

    def _check_fire_answers(self, node: str) -> bool:
        """The fire detector's CheckFire service (in its namespace) answers."""
        import rospy
        from mbzirc_comm_objs.srv import CheckFire
        name = node.rsplit("/", 1)[0] + "/thermal_detection/fire_detected"
        try:
            rospy.wait_for_service(name, timeout=2.0)
            rospy.ServiceProxy(name, CheckFire)()
            return True
        except Exception:  # noqa: BLE001 - not answering is the outcome
            return False

    def _crash(self, f: F.Fault, mon: Monitor) -> None:
        pid = self._pid(f.target)
        if pid is None:
            f.result = {"survived": False, "detail": f"{f.target} was not running before the kill"}
            return
        tracks_before = mon.last_tracks or 0
        objects_before = dict(getattr(mon, "last_objects", {}) or {})
        inputs_before = self._bus_inputs(f.target) if f.check in (F.CHECK_INPUTS, F.CHECK_DETECTIONS) else set()
        self.say(f"kill -9 {f.target} (pid {pid})" + (f", {tracks_before} tracks" if f.check == F.CHECK_TRACKS else ""))
        t_kill = time.monotonic()
        self.recovering.add(f.target)
        self.kill_walls[f.target] = t_kill
        try:
            self._crash_watch(f, mon, pid, t_kill, tracks_before, objects_before, inputs_before)
        finally:
            self.recovering.discard(f.target)

    def _crash_watch(self, f: F.Fault, mon: Monitor, pid: int, t_kill: float, tracks_before: int,
                     objects_before: dict, inputs_before: set) -> None:
        regions_before = mon.regions_before(t_kill) if f.check == F.CHECK_REGIONS else None
        f.result["t_kill"] = mon.sim_time()
        try:
            os.kill(pid, 9)
        except ProcessLookupError:
            pass
        deadline = t_kill + self.cfg.recover_wall_s
        new_pid, functional, verdict = None, False, None
        while time.monotonic() < deadline:
            time.sleep(0.5)
            if new_pid is None:
                p = self._pid(f.target)
                new_pid = p if p is not None and p != pid else None
                t_new = time.monotonic()
            if new_pid is None:
                continue
            functional, verdict = self._functional(f, mon, t_kill, t_new, tracks_before, objects_before,
                                                   inputs_before, regions_before)
            if functional or (f.check in (F.CHECK_TRACKS, F.CHECK_REGIONS) and verdict is not None):
                break                      # judged on the respawned node's first message
        took = time.monotonic() - t_kill
        if f.check == F.CHECK_DECISIONS and new_pid is not None and functional:
            # the heartbeat is back: now watch whether the central unit decides again (bounded in sim time)
            verdict = self._watch_decisions(f, mon)
            functional = verdict["ok"]
        if new_pid is None:
            detail = f"no new process named {f.target} within {self.cfg.recover_wall_s:.0f} s (respawn?)"
        elif not functional:
            why = (verdict or {}).get("detail") or f"{f.check} did not recover"
            detail = f"respawned (pid {new_pid}) but {why}"
        else:
            detail = f"respawned (pid {new_pid}) and {f.check} recovered in {took:.1f} s" + (
                f" ({verdict['detail']})" if verdict and verdict.get("detail") else "")
        f.result.update({"survived": new_pid is not None and functional, "detail": detail, "old_pid": pid,
                         "new_pid": new_pid, "recovery_wall_s": round(took, 1)})
        if verdict is not None:
            f.result[f"{f.check}_check"] = verdict
        if f.check == F.CHECK_TRACKS:
            f.result.update(tracks_before=tracks_before, tracks_after=mon.last_tracks)
            if verdict is not None:
                f.result["tracks_check"] = verdict
        self.say(f"{f.target}: {detail}")

    def _functional(self, f: F.Fault, mon: Monitor, t_kill: float, t_new: float, tracks_before: int,
                    objects_before: dict, inputs_before: set, regions_before) -> tuple[bool, Optional[dict]]:
        """(recovered, verdict details) of a respawned node, by what it must do again (F.CHECK_*)."""
        if f.check == F.CHECK_HEARTBEAT:
            return mon.last_heartbeat_wall > t_kill + 0.5, None
        if f.check == F.CHECK_DECISIONS:
            return mon.last_heartbeat_wall > t_kill + 0.5 and mon.last_seen.get("/central_unit/status", 0) > t_kill + 0.5, None
        if f.check == F.CHECK_DATA_FEED:
            return mon.last_feed_wall.get(f.robot or "", 0.0) > t_kill + 0.5, None
        if f.check == F.CHECK_TRACKS:
            after = mon.first_objects_after(t_kill + 0.5)
            if after is None:
                return False, None
            v = F.compare_tracks(objects_before, after)
            return v["same"] and (mon.last_tracks or 0) >= tracks_before, v
        if f.check == F.CHECK_REGIONS:
            lines = self._region_manager_log()
            since = datetime.now() - timedelta(seconds=time.monotonic() - t_kill)
            after = F.resumed_table(lines, since)            # what the new process says it resumed
            if after is None:
                after = mon.regions_after(t_new)             # else its first /regions
            if after is None:
                return False, None
            if regions_before is None:
                return True, {"detail": "no /regions seen before the kill: kept reservations not checked"}
            (before, before_table), (resumed, resumed_table) = regions_before, after
            removed = (F.removed_between(lines, before_table, resumed_table)
                       if before_table is not None and resumed_table is not None else set())
            v = F.compare_regions(before, resumed, before_table, resumed_table, removed)
            return v["same"], v
        if f.check in (F.CHECK_INPUTS, F.CHECK_DETECTIONS):
            info = self._bus_info(f.target)
            always_on = F.LAZY_NODES.get(f.target.rsplit("/", 1)[-1])
            wanted = always_on is None or not info or bool(F.connected_outputs(info, always_on))
            v = F.judge_io_restored(inputs_before, F.connected_inputs(info), wanted)
            if f.check == F.CHECK_DETECTIONS:
                v["check_fire_answers"] = self._check_fire_answers(f.target)
                if not v["check_fire_answers"]:
                    v["ok"], v["detail"] = False, v["detail"] + "; its CheckFire service does not answer"
            return v["ok"], v
        return True, None

    def _region_manager_log(self) -> list[str]:
        """The region manager's ROS log lines on the ground station, the killed process's and the respawned
        one's (what it resumed, the boxes it removed before the kill)."""
        lines: list[str] = []
        for path in glob.glob(os.path.join(self.out, "logs", C.GROUND_STATION, "*", "region_manager*.log")):
            if "latest" in path or path.endswith("-stdout.log"):
                continue
            with open(path, encoding="utf-8", errors="replace") as fh:
                lines += fh.readlines()
        return lines

    def _watch_decisions(self, f: F.Fault, mon: Monitor) -> dict[str, Any]:
        """Wait (at most DECISION_WITHIN_S sim s after its first status, 3 x that in wall time) for the
        restarted central unit to decide again; then judge its status history since the kill."""
        t_kill = f.result["t_kill"]
        wall_limit = time.monotonic() + 3.0 * F.DECISION_WITHIN_S
        while time.monotonic() < wall_limit:
            with mon.lock:
                hist = list(mon.history)
            v = F.judge_decisions(hist, t_kill, mon.sim_time())
            if v["ok"] and v.get("first_decision_after_s") is not None:
                return v
            after = [t for t, _ in hist if t > t_kill]
            if after and mon.sim_time() - after[0] > F.DECISION_WITHIN_S + 5.0:
                break
            time.sleep(1.0)
        with mon.lock:
            hist = list(mon.history)
        return F.judge_decisions(hist, t_kill, mon.sim_time())

    # the node behind each periodic output (an output whose node is being killed is that fault's to judge)
    @staticmethod
    def _producer(output: str) -> str:
        if output.startswith("/central_unit/"):
            return "/central_unit"
        if output == "/estimated_objects":
            return "/object_estimator"
        return output.rsplit("/", 1)[0] + "/agent"          # /mbzirc2020_<r>/data_feed

    def _expected_outputs(self, mon: Monitor, t_fault: float) -> list[str]:
        """The periodic outputs flowing in the 5 s before a fault, minus those of robots whose link is cut
        and those whose node is down for a kill -9 being judged meanwhile."""
        cut = {f"/mbzirc2020_{r}/data_feed" for r in self.cut_robots}
        return [o for o in mon.flowing(t_fault - 5.0) if o not in cut and self._producer(o) not in self.recovering]

    def _judge_outputs(self, mon: Monitor, expected: list[str], since: float) -> dict[str, Any]:
        """judge_outputs, leaving out outputs whose node was killed meanwhile (judged by that fault)."""
        still = [o for o in expected if self._producer(o) not in self.recovering | self.killed_since(since)]
        v = F.judge_outputs(dict(mon.last_seen), since, still)
        v["expected_outputs"] = still
        return v

    def killed_since(self, wall: float) -> set[str]:
        return {node for node, t in self.kill_walls.items() if t >= wall}

    def _clock_fault(self, f: F.Fault, mon: Monitor) -> None:
        """One /clock message ``jump_s`` back (KIND_CLOCK_JUMP), or /clock counting again from 0 for 1 s
        (KIND_SIM_RESTART: what a restarted simulator sends; ual_sim itself is required and keeps its world,
        so this emulates the restart's clock only); then every periodic output must be published again."""
        from rosgraph_msgs.msg import Clock
        import rospy
        t_fault = time.monotonic()
        expected = self._expected_outputs(mon, t_fault)
        now = mon.sim_time()
        f.result["t_fault"] = now
        if f.kind == F.KIND_CLOCK_JUMP:
            mon.clock_pub.publish(Clock(clock=rospy.Time.from_sec(max(now - (f.jump_s or 10.0), 0.001))))
            self.say(f"/clock: one message {f.jump_s or 10.0:.0f} s in the past (sim t={now:.0f} s)")
        else:
            self.say(f"/clock: counting again from 0 for 1 s (simulator restart, sim t={now:.0f} s)")
            for k in range(1, 21):
                mon.clock_pub.publish(Clock(clock=rospy.Time.from_sec(0.05 * k)))
                time.sleep(0.05)
        time.sleep(min(self.cfg.recover_wall_s, 20.0))
        v = self._judge_outputs(mon, expected, time.monotonic() - 10.0)
        f.result.update({"survived": v["ok"], "detail": v["detail"], "outputs_check": v})
        self.say(f"{f.kind}: {v['detail']}")

    def _wait_up(self, node: str) -> None:
        """Wait (at most recover_wall_s) while ``node`` is down for a kill -9 being judged."""
        deadline = time.monotonic() + self.cfg.recover_wall_s
        while node in self.recovering and time.monotonic() < deadline:
            time.sleep(0.5)

    def _task_exception(self, f: F.Fault, mon: Monitor) -> None:
        """Call the robot's agent's inject_fault (served with ~fault_injection, which the ground-station
        launch sets for UAV 1): the state machine's next step raises, in the idle state (which used to end
        its thread: a zombie) or in the running task; then watch that the agent works on."""
        import rospy
        from std_srvs.srv import Trigger
        name = f"/mbzirc2020_{f.target}/inject_fault"
        self._wait_up(f"/mbzirc2020_{f.target}/agent")     # killed earlier in the schedule: back first
        f.result["t_fault"] = mon.sim_time()
        t0 = time.monotonic()
        try:
            rospy.wait_for_service(name, timeout=30.0)
            rospy.ServiceProxy(name, Trigger)()
        except Exception as e:  # noqa: BLE001 - no injection: the fault could not be run
            f.result.update({"survived": False, "detail": f"could not inject: {type(e).__name__}: {e}"})
            self.say(f"task exception: {f.result['detail']}")
            return
        self.say(f"exception injected into the agent of robot {f.target}")
        watch = 45.0
        time.sleep(watch)
        with mon.lock:
            hist = list(mon.history)
        v = F.judge_working(mon.feeds_since(f.target, t0), hist, f.target, f.result["t_fault"], watch)
        f.result.update({"survived": v["ok"], "detail": v["detail"], "working_check": v,
                         "recovery_wall_s": None})
        self.say(f"task exception: {v['detail']}")

    def _flood(self, f: F.Fault, mon: Monitor) -> None:
        """Publish ObjectDetectionList on robot ``target``'s sensed_objects at ``rate_hz`` for ``duration_s``
        wall seconds, each with one fire far outside the arena at a new place (never confirmed: each is a
        new tentative track); /estimated_objects must keep flowing during it, every output after it."""
        import random
        import rospy
        from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
        topic = f"/mbzirc2020_{f.target}/sensed_objects"
        self._wait_up("/object_estimator")               # a flood of a dead estimator proves nothing
        pub = rospy.Publisher(topic, ObjectDetectionList, queue_size=1000)
        time.sleep(2.0)                                         # let the estimator connect
        expected = self._expected_outputs(mon, time.monotonic())
        rng = random.Random(7)
        period = 1.0 / (f.rate_hz or 1000.0)
        start = time.monotonic()
        end = start + (f.duration_s or 10.0)
        sent, nxt = 0, start
        self.say(f"flooding {topic} at {f.rate_hz or 1000.0:.0f} Hz for {f.duration_s or 10.0:.0f} s")
        while time.monotonic() < end:
            d = ObjectDetection(type=ObjectDetection.TYPE_FIRE)
            d.header.frame_id = "arena"
            d.pose.pose.position.x = rng.uniform(1000.0, 3000.0)
            d.pose.pose.position.y = rng.uniform(1000.0, 3000.0)
            d.pose.pose.orientation.w = 1.0
            pub.publish(ObjectDetectionList(agent_id="flood", objects=[d]))
            sent += 1
            nxt += period
            delay = nxt - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        took = time.monotonic() - start
        gaps = mon.objects_gaps(start, time.monotonic())
        time.sleep(10.0)
        after = self._judge_outputs(mon, expected, time.monotonic() - 8.0)
        v = F.judge_flood(gaps, outputs_after=after)
        v.update(sent=sent, achieved_rate_hz=round(sent / max(took, 1e-6)))
        f.result.update({"survived": v["ok"], "detail": v["detail"] + f" ({sent} messages, "
                         f"{v['achieved_rate_hz']} Hz achieved)", "flood_check": v})
        self.say(f"flood: {f.result['detail']}")

    def _cut(self, f: F.Fault, now: float) -> None:
        host = "ugv" if f.target == "0" else f"uav{f.target}"
        self.lab.set_link(host, False)
        self.cut_robots.add(str(f.target))
        f.result = {"t_cut": now, "wall_cut": datetime.now().isoformat(timespec="milliseconds")}
        self.say(f"link of {host} cut" + (f" for {f.duration_s:.0f} s" if f.duration_s else " for good"))

    # ---- main ----------------------------------------------------------------------------------
    def run(self) -> dict[str, Any]:
        """Build, run, inject, judge, clean up; returns the robustness report (also written to disk)."""
        from mbzirc_robustness.report import format_robustness, merge_fuzz_reports, robustness_report, write_json
        self.out = os.path.abspath(self.cfg.out_dir)
        shutil.rmtree(self.out, ignore_errors=True)
        os.makedirs(self.out, exist_ok=True)
        error = None
        mon = None
        self.lab = NetnsLab()
        install_signal_cleanup(self.lab)
        with self.lab:
            try:
                self._start()
                import rospy
                rospy.init_node("robustness_faults", disable_signals=True)
                mon = Monitor()
                t0 = self._wait_mission(mon)
                self.say(f"mission under way at sim t={t0:.0f} s")
                self._timeline(mon, t0)
            except Exception as exc:  # noqa: BLE001 - reported, then cleaned up
                error = f"{type(exc).__name__}: {exc}"
                self.say(f"ERROR {error}")
            finally:
                if self.gs_proc_running():
                    NetnsLab.stop(self.gs_proc, grace=15.0)  # the recorder writes summary.json on shutdown
        summary = _read_json(os.path.join(self.out, "summary.json"))
        fuzz = merge_fuzz_reports([r for r in (_read_json(p) for p in sorted(
            glob.glob(os.path.join(self.cfg.fuzz_dir, "fuzz_report*.json")))) if r])
        history = mon.history if mon else []
        with open(os.path.join(self.out, "status_history.jsonl"), "w", encoding="utf-8") as fh:
            for t, st in history:  # the central unit's view, for whoever checks a verdict by hand
                fh.write(json.dumps({"t": t, "status": st}) + "\n")
        wall_end = getattr(self, "wall_stop", None) or datetime.now()  # before the hosts were torn down
        cu_kills = [f.result["t_kill"] for f in self.cfg.schedule
                    if f.kind == F.KIND_CRASH and f.check in (F.CHECK_HEARTBEAT, F.CHECK_DECISIONS)
                    and "t_kill" in f.result]
        t_end = getattr(self, "t_stop", None)
        for f in self.cfg.schedule:
            if f.kind in (F.KIND_LINK_CUT, F.KIND_LINK_CUT_PERMANENT) and "t_cut" in f.result:
                t_restore = f.result.get("t_restore")
                f.result.update(F.evaluate_link_cut(history, f.target, f.result["t_cut"], t_restore,
                                                    central_unit_kills=cu_kills, t_end=t_end))
                self._judge_agent(f, history, wall_end)
        rep = robustness_report(fuzz, [F.scenario_entry(f) for f in self.cfg.schedule], summary,
                                robots_lost=F.robots_lost(history))
        if summary is None:
            rep["failures"].append("no mission summary: the mission recorder never finished (mission stopped?)")
        floor = F.mission_floor("short" if self.cfg.stop_when_done else "long")
        perm = [f.target for f in self.cfg.schedule if f.kind == F.KIND_LINK_CUT_PERMANENT]
        rep["mission_floor"] = dict(floor, schedule="short" if self.cfg.stop_when_done else "long",
                                    expected_lost=perm)
        if summary is not None:
            rep["failures"] += F.judge_mission(summary, rep["robots_lost"] or [], floor, expected_lost=perm)
        rep["out_of_order_statuses"] = mon.out_of_order_statuses if mon else 0
        if error:
            rep["failures"].append(f"suite error: {error}")
        rep["checks_passed"] = sum(1 for sc in rep["scenarios"] if sc["survived"])
        rep["checks_failed"] = len(rep["failures"])
        rep["error"] = error
        rep["config"] = {k: v for k, v in vars(self.cfg).items() if k != "schedule"}
        rep["log"] = self.log
        write_json(self.cfg.report_path, rep)
        print(format_robustness(rep), flush=True)
        return rep

    def _judge_agent(self, f: F.Fault, history: list, wall_end: datetime) -> None:
        """Add what the cut robot's agent did by itself (its own log) to the link cut's verdict."""
        cut = datetime.fromisoformat(f.result["wall_cut"])
        restore = datetime.fromisoformat(f.result["wall_restore"]) if f.result.get("wall_restore") else None
        f.result["agent_log_during_cut"] = log = self._agent_log(f, wall_end)
        before = [s for t, s in history if t <= f.result["t_cut"]]
        pos = ((before[-1].get("agents") or {}).get(str(f.target)) or {}).get("pos") if before else None
        flying = f.target != "0" and bool(pos) and len(pos) >= 3 and float(pos[2]) > 1.0
        busy = bool(((before[-1].get("agents") or {}).get(str(f.target)) or {}).get("task")) if before else True
        verdict = F.judge_agent_reaction(log, cut, restore, wall_end, expect_home=flying, busy_at_cut=busy,
                                         lost_after_s=self.cfg.agent_timeout_wall_s,
                                         home_after_s=self.cfg.return_home_wall_s)
        f.result.update(verdict, flying_at_cut=flying, busy_at_cut=busy)
        if not verdict["agent_ok"]:
            f.result["survived"] = False
            problems = [] if f.result.get("detail") in (None, "", "ok") else [f.result["detail"]]
            f.result["detail"] = "; ".join(problems + verdict["agent_problems"])

    def _agent_log(self, f: F.Fault, wall_end: datetime) -> dict[str, Any]:
        """The cut robot's own agent log from the cut until 60 s after the restore (or the end), from its
        host's ROS log dir (the ground station cannot hear it while cut)."""
        host = "ugv" if f.target == "0" else f"uav{f.target}"
        start = datetime.fromisoformat(f.result["wall_cut"])
        end = wall_end
        if f.result.get("wall_restore"):
            end = min(end, datetime.fromisoformat(f.result["wall_restore"]) + timedelta(seconds=60))
        lines: list[str] = []
        for path in glob.glob(os.path.join(self.out, "logs", host, "*", f"mbzirc2020_{f.target}-agent*.log")):
            if "latest" in path or path.endswith("-stdout.log"):
                continue
            with open(path, encoding="utf-8", errors="replace") as fh:
                lines += fh.readlines()
        return F.agent_log_window(lines, start, end)

    def gs_proc_running(self) -> bool:
        return getattr(self, "gs_proc", None) is not None and self.gs_proc.poll() is None

    def _timeline(self, mon: Monitor, t0: float) -> None:
        pending = sorted(self.cfg.schedule, key=lambda f: f.at_s)
        self.threads: list[threading.Thread] = []
        wall_limit = time.monotonic() + 2.0 * self.cfg.duration / max(self.cfg.rtf, 0.1) + 120.0
        restores: list[tuple[float, F.Fault]] = []
        watch_until = 0.0   # monotonic: keep the mission going until then (a cut agent deciding to go home)
        while self.gs_proc.poll() is None:
            now = mon.sim_time() - t0
            for f in [f for f in pending if f.at_s <= now]:
                pending.remove(f)
                f.done = True
                background = {F.KIND_CRASH: self._crash, F.KIND_CLOCK_JUMP: self._clock_fault,
                              F.KIND_SIM_RESTART: self._clock_fault, F.KIND_FLOOD: self._flood,
                              F.KIND_TASK_EXCEPTION: self._task_exception}
                if f.kind in background:  # recovery is watched in the background: the timeline runs on
                    th = threading.Thread(target=background[f.kind], args=(f, mon), daemon=True)
                    th.start()
                    self.threads.append(th)
                else:
                    self._cut(f, mon.sim_time())
                    if f.duration_s:
                        restores.append((f.result["t_cut"] + f.duration_s, f))
                    else:
                        watch_until = max(watch_until, time.monotonic() + self.cfg.agent_timeout_wall_s
                                          + self.cfg.return_home_wall_s + F.BLOCKED_CALL_S + 20.0)
                        # (+ one blocked call: a task busy at the cut may end only after rospy's 60 s timeout)
            for t_restore, f in list(restores):
                if mon.sim_time() >= t_restore:
                    host = "ugv" if f.target == "0" else f"uav{f.target}"
                    self.lab.set_link(host, True)
                    self.cut_robots.discard(str(f.target))
                    f.result["t_restore"] = mon.sim_time()
                    f.result["wall_restore"] = datetime.now().isoformat(timespec="milliseconds")
                    self.say(f"link of {host} restored")
                    restores.remove((t_restore, f))
            if time.monotonic() > wall_limit:
                self.say("wall-time limit reached: stopping the ground station")
                break
            if (self.cfg.stop_when_done and not pending and not restores and time.monotonic() >= watch_until
                    and not any(th.is_alive() for th in self.threads)):
                self.say("every fault judged: stopping the ground station (--stop-when-done)")
                break
            time.sleep(0.5)
        else:
            self.say("ground-station launch ended (mission over)")
        self.wall_stop = datetime.now()
        self.t_stop = mon.sim_time()
        for th in self.threads:
            th.join(3.0 * F.DECISION_WITHIN_S + self.cfg.recover_wall_s + 5.0)
        for f in pending:
            f.result = {"survived": False, "detail": "not run: the mission ended first"}


def _read_json(path: str) -> Optional[dict[str, Any]]:
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return None
