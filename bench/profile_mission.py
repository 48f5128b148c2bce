#!/usr/bin/env python3
"""Where the CPU of a simulated trial goes, per node: py-spy on every Python node of a running mission.

Starts tools/run_mission.sh (SEED, RTF, DURATION as given), waits until the graph is up, attaches
`py-spy record` (non-blocking, so the nodes run at their normal speed; --gil, so that only samples of a
thread running Python count, not threads waiting on a socket) to every node for --seconds wall seconds,
then prints per node kind the functions that took the most samples (self time, and the caller outside
rospy/numpy/the stdlib that led there) and the CPU seconds of every kind over the run.
Raw profiles (collapsed stacks, one file per node) stay in --out for flame graphs
(e.g. `py-spy record --format speedscope`, or https://www.speedscope.app on the .txt files).
    python bench/profile_mission.py --seed 23 --rtf 8 --seconds 60 [--out /tmp/mbzirc_profile]
Needs py-spy (`pip install py-spy` in the venv) and the right to ptrace the nodes (same user, or root).
See bench/PROFILING.md.
"""
from __future__ import annotations

import argparse
import collections
import glob
import os
import shutil
import subprocess
import sys
import time

from _common import ROOT, load_averages
from _node_cpu import KINDS, NodeCpuSampler, descendants, node_kind

# frames that are plumbing, not work: a caller named in the summary is the deepest frame not listed here
PLUMBING = ("threading.py", "socketserver.py", "selectors.py", "socket.py", "rospy/", "rosgraph/", "genpy/",
            "actionlib/", "smach/", "smach_ros/", "<__array_function__", "numpy/", "queue.py")


def python_nodes(root: int) -> dict:
    """{pid: kind} of the Python processes under root that are ROS nodes (their command line has __name:=)."""
    out = {}
    for pid in descendants(root):
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                args = f.read().split(b"\0")
        except OSError:
            continue
        if b"python" in os.path.basename(args[0]) and any(a.startswith(b"__name:=") for a in args):
            name = next(a for a in args if a.startswith(b"__name:="))[8:].decode()
            out[pid] = (node_kind(pid), name)
    return out


def summarise(path: str, top: int) -> list:
    """The `top` leaf functions by samples in a py-spy raw (collapsed) profile, with the deepest frame
    above each that is not plumbing (the project's code that led there); [(share, leaf, caller)]."""
    leaves, total = collections.Counter(), 0
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            stack, _, count = line.rstrip("\n").rpartition(" ")
            if not count.isdigit():
                continue
            n = int(count)
            frames = stack.split(";")
            own = [fr for fr in frames if not any(p in fr for p in PLUMBING)]
            leaves[(frames[-1], own[-1] if own else "")] += n
            total += n
    return [(n / total, leaf, own) for (leaf, own), n in leaves.most_common(top)] if total else []


def short(frame: str) -> str:
    """'func (path/to/file.py:12)' -> 'func (file.py:12)'."""
    name, _, where = frame.partition(" (")
    return f"{name} ({os.path.basename(where)}" if where else name


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=23)
    ap.add_argument("--rtf", type=float, default=8.0)
    ap.add_argument("--duration", type=float, default=1200.0, help="trial length, simulated seconds")
    ap.add_argument("--warmup", type=float, default=20.0, help="wall seconds before profiling starts")
    ap.add_argument("--seconds", type=float, default=60.0, help="wall seconds of profiling")
    ap.add_argument("--rate", type=int, default=25, help="py-spy samples per second")
    ap.add_argument("--top", type=int, default=8)
    ap.add_argument("--out", default="/tmp/mbzirc_profile")
    ap.add_argument("mission_args", nargs="*", metavar="KEY=VALUE",
                    help="more tools/run_mission.sh arguments, e.g. UNCERTAINTY=realistic GNSS_DENIED_INDOORS=1 "
                         "INDOOR_SEARCH=explore")
    args = ap.parse_args()
    spy = shutil.which("py-spy")
    if not spy:
        print("py-spy not found: pip install py-spy (in the venv), then source env.sh", file=sys.stderr)
        return 2
    shutil.rmtree(args.out, ignore_errors=True)
    os.makedirs(args.out)
    mission = subprocess.Popen(["bash", os.path.join(ROOT, "tools", "run_mission.sh"), f"SEED={args.seed}",
                                f"RTF={args.rtf}", f"DURATION={args.duration}", "QUIET=1",
                                f"OUT={os.path.join(args.out, 'mission')}", *args.mission_args],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    sampler = NodeCpuSampler(mission.pid).start()
    time.sleep(args.warmup)
    nodes = python_nodes(mission.pid)
    spies = []
    for pid, (kind, name) in nodes.items():
        raw = os.path.join(args.out, f"{kind}__{name}__{pid}.txt")
        spies.append(subprocess.Popen([spy, "record", "--pid", str(pid), "--duration", str(int(args.seconds)),
                                       "--rate", str(args.rate), "--nonblocking", "--gil", "--format", "raw",
                                       "--output", raw], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    for s in spies:
        s.wait()
    by_kind = collections.defaultdict(list)
    for path in sorted(glob.glob(os.path.join(args.out, "*__*.txt"))):
        by_kind[os.path.basename(path).split("__")[0]].append(path)
    mission.terminate()   # run_mission.sh stops the launch on SIGTERM
    mission.wait()
    sampler.stop()
    cpu = sampler.cpu_by_kind()
    print(f"profiled {len(nodes)} nodes for {args.seconds:.0f} s (load {load_averages()}); CPU-s of the whole "
          f"run per kind: " + ", ".join(f"{k} {cpu[k]:.1f}" for k in KINDS + ("total",)))
    for kind in KINDS:
        for path in by_kind.get(kind, [])[:1]:     # one node of each kind (the others look alike)
            print(f"\n== {kind}: {os.path.basename(path)}")
            for share, leaf, own in summarise(path, args.top):
                print(f"  {100 * share:5.1f} %  {short(leaf)}  <- {short(own) if own else '-'}")
    print(f"\nraw profiles in {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
