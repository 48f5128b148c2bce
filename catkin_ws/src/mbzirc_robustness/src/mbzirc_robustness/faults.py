"""Fault scenarios of a mission (link cuts, kill -9) and how to judge them (pure, no ROS).

Why: the issue asks to prove that the mission survives a UAV's link cut for 60 s, another UAV's link cut
for good, and a kill -9 of each kind of node. The schedule and the verdicts are plain functions of what the
monitor recorded (the central unit's ``/central_unit/status`` JSON history and the node pids), so they are
tested without running a mission.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any, Iterable, Optional

ROSOUT_LINE = re.compile(r"^\[rosout\]\[(\w+)\] (\d{4}-\d\d-\d\d \d\d:\d\d:\d\d),(\d+): (.*)$")

KIND_LINK_CUT = "link_cut"
KIND_LINK_CUT_PERMANENT = "link_cut_permanent"
KIND_CRASH = "crash"
KIND_CLOCK_JUMP = "clock_jump"          # one /clock message ``jump_s`` in the past (a bag with --clock, an NTP step)
KIND_SIM_RESTART = "sim_restart"        # /clock starts again from 0 for a moment (the simulator restarted)
KIND_FLOOD = "flood"                    # a publisher floods a robot's sensed_objects at ``rate_hz``
KIND_TASK_EXCEPTION = "task_exception"  # an exception raised inside a robot's running task

# a floor released while its robot is silent must be taken again within this (sim s), unless nothing is left
RETAKE_WITHIN_S = 90.0
# the central unit must make a decision (an assignment changes) within this after its restart (sim s)
DECISION_WITHIN_S = 90.0

# what must come back after a kill -9, per kind of node (checked by the runner)
CHECK_HEARTBEAT = "heartbeat"          # /central_unit/heartbeat published again
CHECK_DATA_FEED = "data_feed"          # the robot's data_feed published again
CHECK_TRACKS = "tracks"                # /estimated_objects again, with at least the tracks it had before
CHECK_PROCESS = "process"              # a new process answers under the same node name
CHECK_DECISIONS = "decisions"          # central unit: heartbeat and status again, and its decisions go on
CHECK_DETECTIONS = "detections"        # fire detector: inputs connected again and its CheckFire service answers
CHECK_INPUTS = "inputs"                # every input it received before is connected again
CHECK_REGIONS = "regions"              # region manager: every reservation it held is there after the respawn
CHECK_OUTPUTS = "outputs"              # every periodic output of the system published again (clock faults)
CHECK_WORKING = "working"              # task exception: the agent's state machine works on (not a zombie)


@dataclass
class Fault:
    """One scheduled fault, ``at_s`` sim seconds after the mission started.

    Args:
        kind: KIND_LINK_CUT (restored after ``duration_s``), KIND_LINK_CUT_PERMANENT, KIND_CRASH,
            KIND_CLOCK_JUMP, KIND_SIM_RESTART, KIND_FLOOD (for ``duration_s`` at ``rate_hz``) or
            KIND_TASK_EXCEPTION.
        target: robot id (link cuts, flood, task exception), node name (crashes), '/clock' (clock faults).
        check: for crashes, what must come back (CHECK_*).
        robot: for crashes of per-robot nodes, the robot id whose data_feed is checked.
    """

    kind: str
    target: str
    at_s: float
    duration_s: Optional[float] = None
    jump_s: Optional[float] = None      # KIND_CLOCK_JUMP: how far back (s)
    rate_hz: Optional[float] = None     # KIND_FLOOD
    check: str = CHECK_PROCESS
    robot: Optional[str] = None
    done: bool = False
    result: dict[str, Any] = field(default_factory=dict)


def default_schedule(uavs: int = 3, link_cut_s: float = 60.0, start_s: float = 40.0,
                     spacing_s: float = 25.0, ugv: bool = True) -> list[Fault]:
    """The issue's scenarios, link cuts first (judged on an otherwise healthy system): UAV 2's link cut
    for ``link_cut_s`` and UAV 3's for good; once UAV 2 is back, one every ``spacing_s``: kill -9 of the
    fire detector (of the UAV cut for a while: back on its feet), of UAV 1's agent, of the estimator, of the
    region manager, of that UAV's circle detector (water UAVs only) and of the UGV agent, a /clock jump 10 s back, a 1 kHz flood of sensed_objects (10 s), the simulator's clock
    restarting, an exception injected into UAV 1's agent (its idle state or running task), and kill -9 of
    the central unit last (without it nothing else can be judged). With fewer
    UAVs the cuts go to the last UAVs present."""
    cut_temp = str(min(2, uavs))
    cut_perm = str(uavs) if uavs >= 3 else None
    sched = [Fault(KIND_LINK_CUT, cut_temp, start_s, duration_s=link_cut_s)]
    if cut_perm:
        sched.append(Fault(KIND_LINK_CUT_PERMANENT, cut_perm, start_s + spacing_s))
    t = start_s + link_cut_s + spacing_s
    steps: list[Fault] = [
        Fault(KIND_CRASH, f"/mbzirc2020_{cut_temp}/fire_detector", 0, check=CHECK_DETECTIONS, robot=cut_temp),
        Fault(KIND_CRASH, "/mbzirc2020_1/agent", 0, check=CHECK_DATA_FEED, robot="1"),
        Fault(KIND_CRASH, "/object_estimator", 0, check=CHECK_TRACKS),
        Fault(KIND_CRASH, "/region_manager", 0, check=CHECK_REGIONS),
        Fault(KIND_CRASH, f"/mbzirc2020_{cut_temp}/circle_detector", 0, check=CHECK_INPUTS, robot=cut_temp),
        Fault(KIND_CLOCK_JUMP, "/clock", 0, jump_s=10.0, check=CHECK_OUTPUTS),
        Fault(KIND_FLOOD, "1", 0, duration_s=10.0, rate_hz=1000.0, check=CHECK_OUTPUTS),
        Fault(KIND_SIM_RESTART, "/clock", 0, check=CHECK_OUTPUTS),
        Fault(KIND_TASK_EXCEPTION, "1", 0, check=CHECK_WORKING),
    ]
    if ugv:
        steps.insert(5, Fault(KIND_CRASH, "/mbzirc2020_0/agent", 0, check=CHECK_DATA_FEED, robot="0"))
    steps.append(Fault(KIND_CRASH, "/central_unit", 0, check=CHECK_DECISIONS))
    for f in steps:
        f.at_s = t
        sched.append(f)
        t += spacing_s
    return sched


def mission_floor(schedule: str) -> dict[str, Any]:
    """What the mission must still achieve under a schedule's faults (the suite fails below it).

    ``short`` (make test: faults from sim 30 s every 15 s, stopped once every fault is judged, about
    300-400 sim s) and ``long`` (make test-faults: 600 sim s). Robots lost: only the UAV cut for good may be
    dead at the end. Fires: measured on this machine with these faults (see the README's reliability table);
    the floor is set below the worst run seen so that a healthy run passes and a mission that stops passes
    no fire at all."""
    floors = {"short": {"min_fires_out": 1, "max_robots_lost": 1},
              "long": {"min_fires_out": 2, "max_robots_lost": 1}}
    return dict(floors[schedule])


def judge_mission(summary: Optional[dict[str, Any]], lost: list[str], floor: dict[str, Any],
                  expected_lost: Iterable[str] = ()) -> list[str]:
    """Failures of the mission as a whole: fewer fires put out than ``floor['min_fires_out']``, more robots
    lost than ``floor['max_robots_lost']`` or a robot lost that no fault was meant to take."""
    problems = []
    if summary is None:
        return ["no mission summary: fires put out unknown"]
    out = summary.get("fires_extinguished")
    if out is None or out < floor["min_fires_out"]:
        problems.append(f"fires put out {out}/{summary.get('fires_total')} below the floor of "
                        f"{floor['min_fires_out']} for this schedule")
    unexpected = sorted(set(lost) - set(map(str, expected_lost)))
    if len(lost) > floor["max_robots_lost"] or unexpected:
        problems.append(f"robots lost {lost} (allowed: at most {floor['max_robots_lost']}, "
                        f"only {sorted(map(str, expected_lost))})")
    return problems


def judge_decisions(history: list[tuple[float, dict[str, Any]]], t_kill: float, t_end: float,
                    within_s: float = DECISION_WITHIN_S, max_gap_s: float = 15.0) -> dict[str, Any]:
    """Verdict on a central unit restart from its status history: statuses come again and keep coming (no
    gap over ``max_gap_s`` after the first one, until ``t_end``), and it decides again: some robot's task or
    a floor's owner changes within ``within_s`` of its first status (unless every fire is out). A heartbeat
    alone proves only that a process runs, not that the work goes on."""
    after = [(t, s) for t, s in history if t > t_kill]
    if not after:
        return {"ok": False, "detail": "no status from the central unit after the restart"}
    t0 = after[0][0]
    times = [t for t, _ in after] + [t_end]
    gap = max((b - a for a, b in zip(times, times[1:])), default=0.0)

    def decisions(s: dict[str, Any]) -> tuple:
        return (tuple(sorted((r, a.get("task", "")) for r, a in (s.get("agents") or {}).items())),
                tuple(sorted((s.get("floor_owner") or {}).items())), tuple(sorted((s.get("indoor_owner") or {}).items())))

    first = decisions(after[0][1])
    changed = next((t for t, s in after if decisions(s) != first), None)
    problems = []
    if gap > max_gap_s:
        problems.append(f"its status stopped again ({gap:.0f} s without one)")
    if changed is None or changed - t0 > within_s:
        if not _all_fires_out(after[-1][1]) and t_end - t0 >= within_s:
            problems.append(f"no decision (task or floor owner change) within {within_s:.0f} s of its restart")
    return {"ok": not problems, "first_status_after_s": round(t0 - t_kill, 1),
            "first_decision_after_s": None if changed is None else round(changed - t_kill, 1),
            "max_status_gap_s": round(gap, 1), "detail": "; ".join(problems) or "status and decisions go on"}


def judge_outputs(last_seen: dict[str, float], t_fault: float, expected: Iterable[str],
                  settle_s: float = 1.0) -> dict[str, Any]:
    """Verdict on a clock fault: every output in ``expected`` (topic names) was published again after the
    fault (``last_seen``: topic -> monotonic time of its last message, read once the recovery window
    ended; ``t_fault`` the monotonic time of the fault)."""
    silent = sorted(o for o in expected if last_seen.get(o, 0.0) <= t_fault + settle_s)
    return {"ok": not silent, "silent_outputs": silent,
            "detail": f"silent after the fault: {silent}" if silent else "every periodic output published again"}


def judge_flood(gaps_during: list[float], max_gap_s: float = 2.0, outputs_after: Optional[dict[str, Any]] = None
                ) -> dict[str, Any]:
    """Verdict on a flood of sensed_objects: /estimated_objects never paused more than ``max_gap_s`` (wall)
    during it, and every periodic output published after it."""
    worst = max(gaps_during, default=float("inf"))
    problems = []
    if worst > max_gap_s:
        problems.append(f"/estimated_objects paused {worst:.1f} s during the flood (max {max_gap_s:.0f} s)")
    if outputs_after is not None and not outputs_after["ok"]:
        problems.append(outputs_after["detail"])
    return {"ok": not problems, "worst_gap_s": None if worst == float("inf") else round(worst, 2),
            "detail": "; ".join(problems) or "estimated objects kept flowing"}


def connected_inputs(bus_info: list) -> set[str]:
    """Topics a node receives from at least one peer, from its ``getBusInfo`` answer."""
    return {str(e[4]) for e in bus_info if len(e) >= 5 and e[2] in ("i", "b") and e[4] != "/clock"}


def connected_outputs(bus_info: list, always_on: tuple = ("/rosout",)) -> set[str]:
    """Topics a node sends to at least one subscriber, from its ``getBusInfo`` answer; topics ending with one
    of ``always_on`` aside (a lazy node's always-subscribed outputs, e.g. sensed_objects, are no demand)."""
    return {str(e[4]) for e in bus_info if len(e) >= 5 and e[2] == "o"
            and not any(str(e[4]).endswith(a) for a in always_on)}


LAZY_NODES = {"circle_detector": ("/rosout", "/sensed_objects")}   # node name -> outputs that are no demand


def judge_io_restored(before: set[str], after: set[str], outputs_wanted: bool = True) -> dict[str, Any]:
    """Verdict on a restarted node's wiring: every topic it received before the kill it receives again (a
    new process that subscribed to nothing, or whose publishers never connected, does no work), while
    something subscribes to its outputs: a lazy node (circle_detector ~lazy) rightly leaves its inputs
    unconnected until a task demands its output (a run failed it after the demanding task had ended)."""
    missing = sorted(before - after) if outputs_wanted else []
    detail = (f"inputs not connected again: {missing}" if missing else "every input connected again"
              if outputs_wanted else "nothing subscribes to its outputs: a lazy node waits for demand")
    return {"ok": not missing, "inputs_before": sorted(before), "inputs_missing": missing, "detail": detail}


def judge_working(feeds_after: list[tuple[float, str]], history: list[tuple[float, dict[str, Any]]], robot: str,
                  t_inject: float, watch_wall_s: float, min_feeds: int = 3) -> dict[str, Any]:
    """Verdict on an exception injected into a robot's agent: its state machine works on. The agent's
    data_feed (withheld when its state machine stops working) keeps coming during the ``watch_wall_s``
    after the injection (``feeds_after``: (wall s after the injection, active_sub_state)), none says FAILED,
    and the central unit still sees the robot alive at the end. Whether it started a task after the
    injection is reported (``task_after``), not required: a robot may rightly have nothing to do."""
    late = [t for t, _ in feeds_after if t >= watch_wall_s - 10.0]
    failed = [st for _, st in feeds_after if st.startswith("FAILED")]
    after = [(t, s) for t, s in history if t > t_inject]
    alive_end = bool(after) and bool(_agent(after[-1][1], robot).get("alive"))
    tasks = [_agent(s, robot).get("task", "") for _, s in after]
    started = next((b for a, b in zip([""] + tasks, tasks) if b and b != a), None)
    problems = []
    if len(late) < min_feeds:
        problems.append(f"its data_feed stopped ({len(late)} in the last 10 s of {watch_wall_s:.0f} s): "
                        "the state machine died or is stuck")
    if failed:
        problems.append(f"the agent declared itself failed: {failed[0]}")
    if not alive_end:
        problems.append("the central unit does not see it alive")
    return {"ok": not problems, "feeds_after": len(feeds_after), "task_after": started,
            "detail": "; ".join(problems) or ("state machine working" + (f", then ran {started}" if started else ""))}


RESUMED_LINE = re.compile(r"region manager: resumed (\d+) reservations from .*?\): ?(.*)$")
RESUMED_TABLE = re.compile(r"table (\d+)\): ")                    # the number of the table resumed
REMOVED_LINE = re.compile(r"region manager: table (\d+): removed (.*)$")
SHOWN_TABLE = re.compile(r"^table (\d+)$")                       # /regions' DELETEALL marker text


def shown_table(text: str) -> Optional[int]:
    """The table number a /regions message shows (its DELETEALL marker's text), None when it has none."""
    m = SHOWN_TABLE.match(text or "")
    return int(m.group(1)) if m else None


def resumed_regions(lines: Iterable[str], since: datetime) -> Optional[set[str]]:
    """The reservations (``agent/label``) a respawned region manager says it resumed, from its ROS log
    lines after ``since`` (None: no such line). Why not its first /regions: its owners may rightly free
    or replace them in the second before that (a respawned agent settling its regions)."""
    found = resumed_table(lines, since)
    return None if found is None else found[0]


def resumed_table(lines: Iterable[str], since: datetime) -> Optional[tuple[set[str], Optional[int]]]:
    """(reservations, table number or None for a manager that does not number them) of the last
    "resumed" line after ``since``; None: no such line."""
    found = None
    for line in lines:
        m = ROSOUT_LINE.match(line.rstrip("\n"))
        if not m:
            continue
        t = datetime.strptime(m.group(2), "%Y-%m-%d %H:%M:%S").replace(microsecond=int(m.group(3)) * 1000)
        r = RESUMED_LINE.search(m.group(4))
        if r and t >= since:
            n = RESUMED_TABLE.search(m.group(4))
            found = ({x.strip() for x in r.group(2).split(",") if x.strip()}, int(n.group(1)) if n else None)
    return found


def removed_between(lines: Iterable[str], after_table: int, up_to_table: int) -> set[str]:
    """The reservations the region manager logged as removed (freed by their owner or a supervisor, lease
    expired) by tables ``after_table + 1 .. up_to_table`` (it logs them before saving the table)."""
    out: set[str] = set()
    for line in lines:
        m = ROSOUT_LINE.match(line.rstrip("\n"))
        r = REMOVED_LINE.search(m.group(4)) if m else None
        if r and after_table < int(r.group(1)) <= up_to_table:
            out |= {x.strip() for x in r.group(2).split(",") if x.strip()}
    return out


def compare_regions(before: Iterable[str], after: Iterable[str], before_table: Optional[int] = None,
                    after_table: Optional[int] = None, removed: Iterable[str] = ()) -> dict[str, Any]:
    """Verdict on a region manager restart: the reservations (``agent/label``) of its last /regions before
    the kill are all in the table it resumed, except the ones its log says were removed by the tables
    saved after the one shown (``removed``: an owner freed its box between the last /regions the suite
    got and the kill). With table numbers (``before_table`` shown, ``after_table`` resumed), resuming a
    table older than one already shown is a loss by itself: every table shown was on disk before."""
    removed = set(removed) if before_table is not None and after_table is not None else set()
    missing = sorted(set(before) - set(after) - removed)
    older = before_table is not None and after_table is not None and after_table < before_table
    problems = ([f"resumed table {after_table}, older than table {before_table} shown before the kill"] if older else [])
    problems += [f"reservations lost: {missing}"] if missing else []
    freed = sorted((set(before) - set(after)) & removed)
    return {"same": not problems, "before": sorted(before), "missing": missing, "freed_meanwhile": freed,
            "before_table": before_table, "after_table": after_table,
            "detail": "; ".join(problems) or ("every reservation kept" + (
                f" (freed by their owners after the last /regions: {freed})" if freed else ""))}


def _agent(status: dict[str, Any], robot: str) -> dict[str, Any]:
    return (status.get("agents") or {}).get(str(robot)) or {}


def _owned(status: dict[str, Any], robot: str) -> list[str]:
    """Floors (facade ``f<n>``, indoor ``i<n>``) owned by ``robot`` in one status."""
    out = [f"f{k}" for k, v in (status.get("floor_owner") or {}).items() if str(v) == str(robot)]
    out += [f"i{k}" for k, v in (status.get("indoor_owner") or {}).items() if str(v) == str(robot)]
    return out


def _owner(status: dict[str, Any], floor: str) -> Optional[str]:
    d = status.get("floor_owner" if floor[0] == "f" else "indoor_owner") or {}
    v = d.get(floor[1:])
    return None if v is None else str(v)


def _could_take(agent: dict[str, Any]) -> bool:
    """True when a robot of this status could take a released floor now: alive, idle, and a water UAV (a
    status without kind and payload, as older ones, counts as one)."""
    return (bool(agent.get("alive")) and not agent.get("task") and agent.get("kind", "uav") == "uav"
            and agent.get("payload", "water") == "water")


def _free_taker(statuses: list[dict[str, Any]]) -> bool:
    """True when some robot could have taken a released floor in one of these statuses (see _could_take),
    owning no floor itself."""
    return any(_could_take(a) and not _owned(s, r) for s in statuses for r, a in (s.get("agents") or {}).items())


def evaluate_link_cut(history: list[tuple[float, dict[str, Any]]], robot: str, t_cut: float,
                      t_restore: Optional[float], max_gap_s: float = 15.0,
                      central_unit_kills: Iterable[float] = (), t_end: Optional[float] = None,
                      retake_within_s: float = RETAKE_WITHIN_S) -> dict[str, Any]:
    """Verdict on one link cut from the central unit's status history [(sim time, status), ...].

    Survived when: the central unit marked the robot silent, kept running through the cut (no status gap
    longer than ``max_gap_s``), gave every floor the robot owned to another robot (or released it; keeping
    it counts only when no other robot was alive and idle meanwhile), and,
    for a temporary cut, saw the robot alive again after the restore. Whether it got work again is reported.
    A status gap that spans one of ``central_unit_kills`` (sim times of a scheduled kill -9 of the central
    unit) is that fault's, judged by its own verdict, not this cut's.

    ``t_end``: sim time the watching ended (default: the last status). The silence between the last status
    and then counts as a gap: a central unit that sent one status after the cut and went silent failed.
    A floor released while the robot was silent must be taken again (by any robot) within
    ``retake_within_s`` of its release, unless every fire of the status is put out, the watching ended
    first, or no robot could have taken it meanwhile (every living water UAV busy with a floor of its own:
    the one water UAV left works the floors one after the other): released and never retaken while a
    robot was free to take it is work dropped, not reassigned.
    """
    robot = str(robot)
    before = [s for t, s in history if t <= t_cut]
    after = [(t, s) for t, s in history if t > t_cut]
    owned = _owned(before[-1], robot) if before else []
    window_end = t_restore if t_restore is not None else float("inf")
    t_noticed = next((t for t, s in after if t <= window_end + 5.0 and _agent(s, robot)
                      and not _agent(s, robot).get("alive", True)), None)
    t_last = t_end if t_end is not None else (after[-1][0] if after else t_cut)
    times = [t_cut] + [t for t, _ in after if t <= min(window_end, t_last)] + [min(window_end, t_last)]
    kills = list(central_unit_kills)
    gaps = [b - a for a, b in zip(times, times[1:]) if not any(a <= k <= b for k in kills)]
    went_on = bool(after) and (max(gaps) if gaps else 0.0) <= max_gap_s
    reassigned, stuck, kept, dropped = [], [], [], []
    retakes: dict[str, float] = {}
    silent = [s for t, s in after if t_noticed is not None and t_noticed <= t <= window_end]
    # robots that were alive and idle at some point while this one was silent: they could have taken its floor
    free = sorted({r for s in silent for r, a in (s.get("agents") or {}).items()
                   if r != robot and a.get("alive") and not a.get("task")})
    for fl in owned:
        # while it was silent: once it is back the central unit may rightly give it its floor again
        later = [s for t, s in after if t_noticed is not None and t_noticed <= t <= window_end]
        if any(_owner(s, fl) not in (None, robot) for s in later):
            reassigned.append(fl)
        elif later and _owner(later[-1], fl) is None:
            # released: fine only when someone takes it again in time (or nothing is left to do there)
            t_rel = next((t for t, s in after if t >= t_noticed and _owner(s, fl) is None), None)
            retaken = next((t for t, s in after if t_rel is not None and t > t_rel and _owner(s, fl) is not None), None)
            horizon = t_last
            if retaken is not None and retaken - t_rel <= retake_within_s:
                reassigned.append(fl)
                retakes[fl] = round(retaken - t_rel, 1)
            elif _all_fires_out(after[-1][1]) or horizon - t_rel < retake_within_s:
                reassigned.append(fl)  # nothing left to do there, or too little time watched to tell
            elif not _free_taker([s for t, s in after if t_rel <= t <= t_rel + retake_within_s]):
                kept.append(fl)        # no robot could take it in time: not the central unit's fault
            else:
                dropped.append(fl)
        elif not free:
            kept.append(fl)  # nobody was free to take it: not the central unit's fault
        else:
            stuck.append(fl)
    timeline = {fl: owner_changes(history, fl, t_cut - 10.0) for fl in owned}
    res: dict[str, Any] = {"robot": robot, "t_cut": t_cut, "t_restore": t_restore, "t_noticed": t_noticed,
                           "owner_timeline": timeline,
                           "floors_owned_at_cut": owned, "floors_reassigned": reassigned,
                           "floors_not_reassigned": stuck, "floors_kept_no_free_robot": kept,
                           "floors_released_not_retaken": dropped, "retaken_after_s": retakes,
                           "free_robots_during_silence": free, "mission_went_on": went_on}
    problems = []
    if t_noticed is None:
        problems.append("central unit never marked the robot silent")
    if not went_on:
        problems.append("central unit status stopped during the cut")
    if stuck:
        problems.append(f"floors still owned by the silent robot although {free} were free: {stuck}")
    if dropped:
        problems.append(f"floors released but not taken again within {retake_within_s:.0f} s: {dropped}")
    if t_restore is not None:
        back = [(t, s) for t, s in history if t > t_restore and _agent(s, robot).get("alive")]
        res["t_back"] = back[0][0] if back else None
        res["got_work_again"] = any(_agent(s, robot).get("task") for _, s in back)
        if not back:
            problems.append("robot never came back after the link was restored")
    res["survived"] = not problems
    res["detail"] = "; ".join(problems) if problems else "ok"
    return res


def _all_fires_out(status: dict[str, Any]) -> bool:
    """Every fire the central unit knows is put out (nothing left to assign)."""
    fires = status.get("fires") or []
    return bool(fires) and all(str(f.get("status", "")).upper() in ("EXTINGUISHED", "INACTIVE", "4", "0")
                               for f in fires)


def owner_changes(history: list[tuple[float, dict[str, Any]]], floor: str, since: float) -> list[list[Any]]:
    """[[sim time, owner], ...] each time the owner of ``floor`` (``f<n>`` / ``i<n>``) changed."""
    out: list[list[Any]] = []
    for t, s in history:
        if t < since:
            continue
        o = _owner(s, floor)
        if not out or out[-1][1] != o:
            out.append([round(t, 1), o])
    return out


def robots_lost(history: list[tuple[float, dict[str, Any]]]) -> list[str]:
    """Robots the central unit considers dead in its last status."""
    if not history:
        return []
    return sorted(r for r, a in (history[-1][1].get("agents") or {}).items() if not a.get("alive", False))


# mbzirc_comm_objs/Object statuses that are final (set through /set_object_status): must survive anything
FINAL_STATUSES = {0: "INACTIVE", 4: "EXTINGUISHED"}
LIVE_STATUSES = {1, 3}  # ACTIVE <-> LOST follows from time without detections, also while the estimator is down


def compare_tracks(before: dict[int, int], after: dict[int, int]) -> dict[str, Any]:
    """Verdict on an estimator restart: its tracks ({id: status}) before the kill and the first published
    after it. The same when every id is still there and every final status (INACTIVE, EXTINGUISHED) kept;
    ACTIVE <-> LOST may change (the restarted estimator ages the tracks it did not hear about meanwhile)."""
    missing = sorted(set(before) - set(after))
    changed = {i: [before[i], after[i]] for i in before if i in after and before[i] != after[i]}
    bad = {i: v for i, v in changed.items() if not (v[0] in LIVE_STATUSES and v[1] in LIVE_STATUSES)}
    problems = []
    if missing:
        problems.append(f"{len(missing)} of {len(before)} ids gone: {missing[:10]}")
    if bad:
        problems.append(f"statuses changed: {dict(list(bad.items())[:10])}")
    return {"same": not problems, "ids_before": len(before), "ids_after": len(after), "missing_ids": missing,
            "status_changes": {str(k): v for k, v in changed.items()},
            "final_before": sum(1 for v in before.values() if v in FINAL_STATUSES),
            "detail": "; ".join(problems) if problems else "same ids and statuses"}


def scenario_entry(f: Fault) -> dict[str, Any]:
    """A fault and its result as one entry of the robustness report."""
    entry = {"kind": f.kind, "target": f.target, "at_s": f.at_s, "survived": bool(f.result.get("survived")),
             "detail": f.result.get("detail", "not run" if not f.done else "")}
    if f.duration_s is not None:
        entry["duration_s"] = f.duration_s
    entry.update({k: v for k, v in f.result.items() if k not in entry})
    return entry


def agent_log_window(lines: Iterable[str], start: datetime, end: datetime, keep: int = 4) -> dict[str, Any]:
    """What a robot's agent logged (its rospy log file, ``[rosout]`` lines) between ``start`` and ``end``.

    Why: a cut robot cannot be heard from the ground station; its own log says whether it noticed the
    heartbeat loss and what it did (stop, hold, return home) - or that it was stuck and said nothing.
    Also returns the wall times (ISO) of the lines of each reaction (``events``: name -> times, at most
    20 each), for ``judge_agent_reaction``.
    """
    inside: list[tuple[datetime, str]] = []
    for line in lines:
        m = ROSOUT_LINE.match(line.rstrip("\n"))
        if not m:
            continue
        t = datetime.strptime(m.group(2), "%Y-%m-%d %H:%M:%S").replace(microsecond=int(m.group(3)) * 1000)
        if start <= t <= end:
            inside.append((t, f"{m.group(2)[11:]} {m.group(1)}: {m.group(4)[:160]}"))
    inside.sort(key=lambda x: x[0])
    events: dict[str, list[str]] = {}
    for t, text in inside:
        for name, pattern in AGENT_REACTIONS.items():
            if pattern.search(text) and len(events.setdefault(name, [])) < 20:
                events[name].append(t.isoformat(timespec="milliseconds"))
    texts = [x for _, x in inside]
    hb = [x for x in texts if "heartbeat" in x.lower()]
    return {"lines": len(texts), "heartbeat_lines": hb[:keep], "first": texts[:keep], "last": texts[-keep:],
            "noticed_heartbeat_loss": "heartbeat_lost" in events, "events": events}


# what an agent logs when it reacts to the central unit's heartbeat (mbzirc_agents robot_agent / uav_agent)
AGENT_REACTIONS = {
    "heartbeat_lost": re.compile(r"heartbeat lost", re.I),
    # the go-home task starting (smach's transition out of the idle state), or the agent saying why it
    # cannot: never a line that merely names the task ("go_home_and_refill failed", "[go_home_and_refill/..]")
    "return_home": re.compile(r"transitioning 'DEFAULT':'go_home_and_refill'-->|cannot go home", re.I),
    "heartbeat_back": re.compile(r"heartbeat back", re.I),
    # the running task ended (smach: back to the idle state), whatever its outcome
    "task_ended": re.compile(r"transitioning '(?!DEFAULT')[^']+':'[^']+'-->'DEFAULT'"),
}


# rospy's socket timeout (rospy.impl.masterslave): a call to an unreachable master or service ends after it
BLOCKED_CALL_S = 60.0


def judge_agent_reaction(log: dict[str, Any], wall_cut: datetime, wall_restore: Optional[datetime],
                         wall_end: datetime, expect_home: bool, busy_at_cut: bool = False,
                         lost_after_s: float = 5.0,
                         home_after_s: float = 60.0, slack_s: float = 15.0) -> dict[str, Any]:
    """Verdict on what a cut robot did by itself, from ``agent_log_window`` over [cut, end].

    The agent (wall-clock watchdog) must log the heartbeat loss within ``lost_after_s + slack_s`` of the
    cut; when the link stayed down long enough and the robot was flying (``expect_home``), it must have
    started going home (or said why it could not) ``lost_after_s + home_after_s`` after the cut, or, when
    a task was running (``busy_at_cut``), once that task ended (the watchdog preempts it, and goes home only
    when no task runs) - within ``slack_s``. A task that never ends while cut (blocked in calls to the
    unreachable ground station) is a failure: every call of an agent is bounded in wall time, so its task
    must end. After a restore the agent must log that the heartbeat is back. ``agent_unverified`` stays
    in the result (always empty) for readers of older reports.
    Returns {"agent_ok", "agent_problems", "agent_checked", "agent_unverified"}.
    """
    ev = {k: [datetime.fromisoformat(x) for x in v] for k, v in (log.get("events") or {}).items()}
    problems, checked = [], []

    def within(name: str, t0: datetime, limit: Optional[float], not_before: float = 0.0) -> bool:
        """A line of reaction ``name`` between t0 + not_before and t0 + limit (s)."""
        return any(not_before <= (t - t0).total_seconds() and (limit is None or (t - t0).total_seconds() <= limit)
                   for t in ev.get(name, []))

    down_until = wall_restore or wall_end
    if (down_until - wall_cut).total_seconds() >= lost_after_s + 5.0:   # it had the time to notice
        checked.append("heartbeat_lost")
        if not within("heartbeat_lost", wall_cut, lost_after_s + slack_s):
            problems.append(f"its agent logged no heartbeat loss within {lost_after_s + slack_s:.0f} s (wall) "
                            f"of the cut ({log.get('lines', 0)} lines logged while cut)")
    home_at = lost_after_s + home_after_s
    unverified = []
    if expect_home and (down_until - wall_cut).total_seconds() >= home_at + slack_s:
        ended = sorted((t - wall_cut).total_seconds() for t in ev.get("task_ended", []) if t >= wall_cut)
        free_at = max(home_at, ended[0]) if busy_at_cut and ended else (None if busy_at_cut else home_at)
        if free_at is None:
            # every agent call is bounded in wall time (mbzirc_agents bounded_call): a task that never ends
            # while cut is a stuck agent, not an unverifiable case
            checked.append("return_home")
            problems.append("its task never ended while cut, so it never started going home")
        elif (down_until - wall_cut).total_seconds() >= free_at + slack_s:
            checked.append("return_home")
            # not before the watchdog could order it: a go-home task cut short by the loss does not count
            if not within("return_home", wall_cut, free_at + slack_s, not_before=home_at - 1.0):
                problems.append(f"its agent did not start going home by {free_at + slack_s:.0f} s (wall) after "
                                f"the cut (due at {home_at:.0f} s" + (f", its task ended at {free_at:.0f} s)"
                                                                      if busy_at_cut else ")"))
    if wall_restore is not None and (wall_end - wall_restore).total_seconds() >= 60.0:
        checked.append("heartbeat_back")
        if not within("heartbeat_back", wall_restore, None):
            problems.append("its agent never logged the heartbeat back after the restore")
    return {"agent_ok": not problems, "agent_problems": problems, "agent_checked": checked,
            "agent_unverified": unverified}
