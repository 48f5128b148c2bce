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

# what must come back after a kill -9, per kind of node (checked by the runner)
CHECK_HEARTBEAT = "heartbeat"          # /central_unit/heartbeat published again
CHECK_DATA_FEED = "data_feed"          # the robot's data_feed published again
CHECK_TRACKS = "tracks"                # /estimated_objects again, with at least the tracks it had before
CHECK_PROCESS = "process"              # a new process answers under the same node name


@dataclass
class Fault:
    """One scheduled fault, ``at_s`` sim seconds after the mission started.

    Args:
        kind: KIND_LINK_CUT (restored after ``duration_s``), KIND_LINK_CUT_PERMANENT or KIND_CRASH.
        target: robot id (link cuts) or node name (crashes).
        check: for crashes, what must come back (CHECK_*).
        robot: for crashes of per-robot nodes, the robot id whose data_feed is checked.
    """

    kind: str
    target: str
    at_s: float
    duration_s: Optional[float] = None
    check: str = CHECK_PROCESS
    robot: Optional[str] = None
    done: bool = False
    result: dict[str, Any] = field(default_factory=dict)


def default_schedule(uavs: int = 3, link_cut_s: float = 60.0, start_s: float = 40.0,
                     spacing_s: float = 25.0) -> list[Fault]:
    """The issue's scenarios, link cuts first (judged on an otherwise healthy system): UAV 2's link cut
    for ``link_cut_s`` and UAV 3's for good; once UAV 2 is back, kill -9 of a detector, an agent, the
    estimator and the central unit (last: without it nothing else can be judged). With fewer UAVs the cuts
    go to the last UAVs present."""
    cut_temp = str(min(2, uavs))
    cut_perm = str(uavs) if uavs >= 3 else None
    sched = [Fault(KIND_LINK_CUT, cut_temp, start_s, duration_s=link_cut_s)]
    if cut_perm:
        sched.append(Fault(KIND_LINK_CUT_PERMANENT, cut_perm, start_s + spacing_s))
    t = start_s + link_cut_s + spacing_s
    for node, check, robot in ((f"/mbzirc2020_{cut_temp}/fire_detector", CHECK_PROCESS, cut_temp),
                               ("/mbzirc2020_1/agent", CHECK_DATA_FEED, "1"),
                               ("/object_estimator", CHECK_TRACKS, None),
                               ("/central_unit", CHECK_HEARTBEAT, None)):
        sched.append(Fault(KIND_CRASH, node, t, check=check, robot=robot))
        t += spacing_s
    return sched


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


def evaluate_link_cut(history: list[tuple[float, dict[str, Any]]], robot: str, t_cut: float,
                      t_restore: Optional[float], max_gap_s: float = 15.0) -> dict[str, Any]:
    """Verdict on one link cut from the central unit's status history [(sim time, status), ...].

    Survived when: the central unit marked the robot silent, kept running through the cut (no status gap
    longer than ``max_gap_s``), gave every floor the robot owned to another robot (or released it; keeping
    it counts only when no other robot was alive and idle meanwhile), and,
    for a temporary cut, saw the robot alive again after the restore. Whether it got work again is reported.
    """
    robot = str(robot)
    before = [s for t, s in history if t <= t_cut]
    after = [(t, s) for t, s in history if t > t_cut]
    owned = _owned(before[-1], robot) if before else []
    window_end = t_restore if t_restore is not None else float("inf")
    t_noticed = next((t for t, s in after if t <= window_end + 5.0 and _agent(s, robot)
                      and not _agent(s, robot).get("alive", True)), None)
    times = [t_cut] + [t for t, _ in after if t <= min(window_end, after[-1][0] if after else t_cut)]
    gaps = [b - a for a, b in zip(times, times[1:])]
    went_on = bool(after) and (max(gaps) if gaps else 0.0) <= max_gap_s
    reassigned, stuck, kept = [], [], []
    silent = [s for t, s in after if t_noticed is not None and t_noticed <= t <= window_end]
    # robots that were alive and idle at some point while this one was silent: they could have taken its floor
    free = sorted({r for s in silent for r, a in (s.get("agents") or {}).items()
                   if r != robot and a.get("alive") and not a.get("task")})
    for fl in owned:
        later = [s for t, s in after if t_noticed is not None and t >= t_noticed]
        if any(_owner(s, fl) not in (None, robot) for s in later):
            reassigned.append(fl)
        elif later and _owner(later[-1], fl) is None:
            reassigned.append(fl)  # released: no longer anyone's job (done, or next search pending)
        elif not free:
            kept.append(fl)  # nobody was free to take it: not the central unit's fault
        else:
            stuck.append(fl)
    timeline = {fl: owner_changes(history, fl, t_cut - 10.0) for fl in owned}
    res: dict[str, Any] = {"robot": robot, "t_cut": t_cut, "t_restore": t_restore, "t_noticed": t_noticed,
                           "owner_timeline": timeline,
                           "floors_owned_at_cut": owned, "floors_reassigned": reassigned,
                           "floors_not_reassigned": stuck, "floors_kept_no_free_robot": kept,
                           "free_robots_during_silence": free, "mission_went_on": went_on}
    problems = []
    if t_noticed is None:
        problems.append("central unit never marked the robot silent")
    if not went_on:
        problems.append("central unit status stopped during the cut")
    if stuck:
        problems.append(f"floors still owned by the silent robot although {free} were free: {stuck}")
    if t_restore is not None:
        back = [(t, s) for t, s in history if t > t_restore and _agent(s, robot).get("alive")]
        res["t_back"] = back[0][0] if back else None
        res["got_work_again"] = any(_agent(s, robot).get("task") for _, s in back)
        if not back:
            problems.append("robot never came back after the link was restored")
    res["survived"] = not problems
    res["detail"] = "; ".join(problems) if problems else "ok"
    return res


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
    """
    inside: list[str] = []
    for line in lines:
        m = ROSOUT_LINE.match(line.rstrip("\n"))
        if not m:
            continue
        t = datetime.strptime(m.group(2), "%Y-%m-%d %H:%M:%S").replace(microsecond=int(m.group(3)) * 1000)
        if start <= t <= end:
            inside.append(f"{m.group(2)[11:]} {m.group(1)}: {m.group(4)[:160]}")
    hb = [x for x in inside if "heartbeat" in x.lower()]
    return {"lines": len(inside), "heartbeat_lines": hb[:keep], "first": inside[:keep], "last": inside[-keep:],
            "noticed_heartbeat_loss": bool(hb)}
