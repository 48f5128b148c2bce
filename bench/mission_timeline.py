#!/usr/bin/env python3
"""Where a mission's time went: per robot, the sim seconds spent idle, in each task, waiting for a shared
region, and on fires that were already out; then each fire's time out and the central unit's goals in order.

Reads a run dir of tools/run_mission.sh (summary.json, estimator_tracks.json, ros_logs/*/rosout.log); runs
nothing. The central unit logs each goal (`<id> <- <task> (<why>)`) and each outcome (`<id> <task> -> STATE
...`); the region manager logs `<id>/<region> refused: ...` and `... granted after waiting`.
    python bench/mission_timeline.py RUN_DIR [RUN_DIR ...] [--goals] [--until T]
    python bench/mission_timeline.py RUN_DIR [RUN_DIR ...] --share 2,3     (the water UAVs over all runs)
Times are counted up to the time all fires were out (else the end of the run), or --until. The purposes
and idle add up to that time; the columns in parentheses (region waits, failed goals, goals on fires already
out) are parts of them, counted again.
Not a benchmark (no figures of the code's speed): an analysis of one run's log, to find the waste.
"""
from __future__ import annotations

import argparse
import glob
import json
import math
import os
import re
from collections import defaultdict
from dataclasses import dataclass, field
from typing import Optional

TOPICS = re.compile(r"\[topics: [^]]*\] ")
GOAL = re.compile(r"central_unit: (\S+) <- (\S+) \((.*)\)\s*$")
RESULT = re.compile(r"central_unit: (\S+) (\S+) -> ([A-Z]+) ?(.*)$")
REFUSED = re.compile(r"region manager: (\S+)/(\S+) refused")
GRANTED = re.compile(r"region manager: (\S+)/(\S+) granted after waiting")
FIRE_TASKS = ("go_to_facade_fire", "extinguish_facade_fire", "extinguish_indoor_fire", "extinguish_ground_fire")
MATCH_RADIUS = 2.5  # m between an estimator track and the true fire it stands for


@dataclass
class Goal:
    agent: str
    task: str
    why: str
    start: float
    end: Optional[float] = None
    state: str = ""
    message: str = ""
    fire_track: Optional[int] = None

    def purpose(self) -> str:
        """What the goal was for, from its task and the central unit's reason."""
        if "refill" in self.why or self.task == "go_home_and_refill":
            return "refill trip"
        if "no work left" in self.why or "for good" in self.why:
            return "home for good"
        if self.task in FIRE_TASKS:
            return "fire work"
        if self.task in ("take_off", "land"):
            return "take-off/land"
        if self.task in ("follow_path", "go_to"):
            return "transit"
        if self.task == "search_indoor" and ("leaving" in self.why or "viewpoint" in self.why):
            return "indoor moves"
        if self.task in ("search_facade", "search_indoor", "look_for_ground_fires", "enter_building"):
            return "search"
        return self.task


@dataclass
class Run:
    summary: dict
    goals: list = field(default_factory=list)
    waits: dict = field(default_factory=lambda: defaultdict(list))   # agent -> [(start, end, region)]
    tracks: dict = field(default_factory=dict)                        # track id -> true fire id


def rosout_lines(run_dir: str) -> list[str]:
    logs = [p for p in glob.glob(os.path.join(run_dir, "ros_logs", "*", "rosout.log"))
            if os.path.basename(os.path.dirname(p)) != "latest"]
    lines = []
    for p in logs:
        with open(p, errors="replace") as f:
            lines += [TOPICS.sub("", ln.rstrip("\n")) for ln in f]
    return sorted(lines, key=lambda ln: float(ln.split(" ", 1)[0]) if ln[:1].isdigit() else 0.0)


def track_to_fire(run_dir: str, fires: list[dict]) -> dict[int, str]:
    """Estimator track id -> the nearest true fire (within MATCH_RADIUS), from estimator_tracks.json."""
    path = os.path.join(run_dir, "estimator_tracks.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        tracks = json.load(f).get("tracks", [])
    out = {}
    for t in tracks:
        best = min(fires, key=lambda fi: math.dist(fi["position"], t["position"]), default=None)
        if best is not None and math.dist(best["position"], t["position"]) <= MATCH_RADIUS:
            out[int(t["id"])] = best["id"]
    return out


def load(run_dir: str) -> Run:
    with open(os.path.join(run_dir, "summary.json")) as f:
        run = Run(json.load(f))
    run.tracks = track_to_fire(run_dir, run.summary.get("fires", []))
    open_goal: dict[str, Goal] = {}
    refused_at: dict[tuple[str, str], tuple[float, str]] = {}
    for ln in rosout_lines(run_dir):
        try:
            t = float(ln.split(" ", 1)[0])
        except ValueError:
            continue
        if "/central_unit" in ln:
            m = GOAL.search(ln)
            if m:
                g = Goal(m[1], m[2], m[3], t)
                num = re.search(r"fire (\d+)", g.why)
                g.fire_track = int(num[1]) if num and g.task in FIRE_TASKS else None
                open_goal[g.agent] = g
                run.goals.append(g)
                continue
            m = RESULT.search(ln)
            if m and m[1] in open_goal and open_goal[m[1]].task == m[2]:
                g = open_goal.pop(m[1])
                g.end, g.state, g.message = t, m[3], m[4]
        elif "/region_manager" in ln:
            m = REFUSED.search(ln)
            if m and (m[1], m[2]) not in refused_at:
                refused_at[(m[1], m[2])] = (t, ln.split("refused: ", 1)[-1])
                continue
            m = GRANTED.search(ln)
            if m and (m[1], m[2]) in refused_at:
                t0, why = refused_at.pop((m[1], m[2]))
                run.waits[m[1]].append((t0, t, why))
    return run


def clip(a: float, b: float, end: float) -> float:
    return max(0.0, min(b, end) - min(a, end))


def out_times(run: Run) -> dict[str, float]:
    return {f["id"]: f["t_extinguished"] for f in run.summary.get("fires", []) if f.get("t_extinguished")}


def breakdown(run: Run, end: float) -> dict[str, dict[str, float]]:
    """agent -> {purpose: s, 'idle': s, 'region waits': s, 'failed goals': s, 'on fires already out': s}."""
    out_at = out_times(run)
    per: dict[str, dict[str, float]] = defaultdict(lambda: defaultdict(float))
    busy: dict[str, float] = defaultdict(float)
    for g in run.goals:
        stop = g.end if g.end is not None else end
        d = clip(g.start, stop, end)
        row = per[g.agent]
        row[g.purpose()] += d
        busy[g.agent] += d
        if g.state and g.state != "SUCCEEDED":
            row["(failed goals)"] += d
        true_fire = run.tracks.get(g.fire_track) if g.fire_track is not None else None
        if true_fire is not None and true_fire in out_at and g.start >= out_at[true_fire]:
            row["(on fires already out)"] += d
    for agent, waits in run.waits.items():
        per[agent]["(region waits)"] += sum(clip(a, b, end) for a, b, _ in waits)
    for agent in per:
        per[agent]["idle"] = max(0.0, end - busy[agent])
    return per


ORDER = ("search", "indoor moves", "fire work", "transit", "refill trip", "take-off/land", "home for good",
         "idle", "(region waits)", "(failed goals)", "(on fires already out)")


def report(run_dir: str, show_goals: bool, until: Optional[float]) -> None:
    run = load(run_dir)
    s = run.summary
    end = until or s.get("all_out_time_s") or s.get("sim_time_s") or 0.0
    print(f"== {run_dir}: seed {s.get('seed')}, {s.get('fires_extinguished')}/{s.get('fires_total')} out, "
          f"all out {s.get('all_out_time_s')}, counted up to {end:.0f} s")
    fires = sorted(s.get("fires", []), key=lambda f: f.get("t_extinguished") or 1e9)
    print("fires out: " + ", ".join(f"{f['id']} {f['t_extinguished']:.0f} by {f['extinguished_by']}"
                                    if f.get("t_extinguished") else f"{f['id']} NOT ({f.get('progress', 0):.2f})"
                                    for f in fires))
    per = breakdown(run, end)
    extra = sorted({k for row in per.values() for k in row} - set(ORDER))
    cols = list(ORDER) + extra
    print(f"{'robot':>5} " + " ".join(f"{c[:13]:>13}" for c in cols))
    for agent in sorted(per):
        print(f"{agent:>5} " + " ".join(f"{per[agent].get(c, 0.0):13.0f}" for c in cols))
    for agent in sorted(run.waits):
        long = [(a, b, why) for a, b, why in run.waits[agent] if b - a >= 10 and a < end]
        for a, b, why in long:
            print(f"   region wait {agent}: {a:.0f}-{b:.0f} s ({b - a:.0f} s) {why[:70]}")
    if show_goals:
        for g in run.goals:
            if g.start > end:
                break
            stop = f"{g.end:6.0f}" if g.end is not None else "     -"
            fire = run.tracks.get(g.fire_track, "") if g.fire_track is not None else ""
            print(f"  {g.start:6.0f}{stop} {g.agent} {g.purpose():13} {g.task:22} {g.state[:4]:4} "
                  f"{fire:6} {g.why[:60]} | {g.message[:60]}")


def shares(run_dirs: list[str], agents: set[str]) -> None:
    """Share of the given robots' time (each counted up to its run's end) per purpose, over all runs."""
    total: dict[str, float] = defaultdict(float)
    span = 0.0
    for d in run_dirs:
        run = load(d)
        end = run.summary.get("all_out_time_s") or run.summary.get("sim_time_s") or 0.0
        for agent, row in breakdown(run, end).items():
            if agent in agents:
                span += end
                for k, v in row.items():
                    total[k] += v
    print(f"robots {sorted(agents)} over {len(run_dirs)} runs ({span:.0f} robot-s): " + ", ".join(
        f"{k} {100 * v / span:.0f} %" for k, v in sorted(total.items(), key=lambda kv: -kv[1])))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="run dirs (tools/run_mission.sh OUT=...)")
    ap.add_argument("--goals", action="store_true", help="list every goal with its purpose and outcome")
    ap.add_argument("--until", type=float, help="count up to this sim time (default: all out, else the end)")
    ap.add_argument("--share", metavar="IDS", help="only the share of time per purpose of these robots over "
                    "all the runs, e.g. 2,3 (the water UAVs)")
    args = ap.parse_args()
    if args.share:
        shares(args.runs, set(args.share.split(",")))
        return
    for r in args.runs:
        report(r, args.goals, args.until)


if __name__ == "__main__":
    main()
