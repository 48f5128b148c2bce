"""CPU time of every process of a running launch, summed per node kind, read from /proc.

Not a benchmark itself: bench_mission.py samples a trial with it, and bench/PROFILING.md uses it by hand
    python bench/_node_cpu.py <pid of roslaunch> [seconds]
A node's kind is its executable's name (uav_agent -> agents, ual_sim_node -> ual_sim, ...), so the figures
do not depend on which package holds a node. Every descendant of the given process counts (roslaunch,
rosmaster and rosout included, under "others"); a process's CPU is user + system time, sampled twice a
second, so a node that exits between two samples loses at most half a second of its CPU.
"""
from __future__ import annotations

import os
import sys
import threading
import time

# executable (basename of the script or binary) -> node kind; anything else is "others"
KIND_OF_EXECUTABLE = {
    "uav_agent": "agents", "ugv_agent": "agents",
    "ual_sim_node": "ual_sim",
    "fire_detector": "fire_detector",
    "circle_detector": "circle_detector",
    "central_unit_node.py": "central_unit",
    "object_estimator": "object_estimator",
    "hector_mapping": "hector_mapping",
    "indoor_pose": "indoor_pose",
}
KINDS = ("agents", "ual_sim", "fire_detector", "circle_detector", "central_unit", "object_estimator",
         "hector_mapping", "indoor_pose", "others")
TICKS_PER_S = os.sysconf("SC_CLK_TCK")


def process_stat(pid: int):
    """(parent pid, user + system CPU seconds) of a process, or None if it is gone."""
    try:
        with open(f"/proc/{pid}/stat", encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # the command name may hold spaces and parentheses
    return int(fields[1]), (int(fields[11]) + int(fields[12])) / TICKS_PER_S


def node_kind(pid: int) -> str:
    """The kind of a process from its command line: the first argument that names a known executable."""
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            args = f.read().split(b"\0")
    except OSError:
        return "others"
    for arg in args[:3]:  # [python, script, ...] or [binary, ...]
        kind = KIND_OF_EXECUTABLE.get(os.path.basename(arg.decode(errors="replace")))
        if kind:
            return kind
    return "others"


def descendants(root: int) -> dict:
    """{pid: (kind-less) CPU seconds} of root and every process below it."""
    stats = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            s = process_stat(int(name))
            if s:
                stats[int(name)] = s
    children = {}
    for pid, (ppid, _) in stats.items():
        children.setdefault(ppid, []).append(pid)
    out, todo = {}, [root]
    while todo:
        pid = todo.pop()
        if pid in stats:
            out[pid] = stats[pid][1]
            todo.extend(children.get(pid, ()))
    return out


class NodeCpuSampler:
    """Samples the CPU of a process tree in a background thread until stop(); cpu_by_kind() sums it."""

    def __init__(self, root_pid: int, period_s: float = 0.5):
        self.root, self.period = root_pid, period_s
        self.cpu = {}    # pid -> last CPU seconds seen
        self.kind = {}   # pid -> node kind
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self) -> "NodeCpuSampler":
        self._thread.start()
        return self

    def sample(self) -> None:
        for pid, cpu in descendants(self.root).items():
            if pid not in self.kind:
                self.kind[pid] = node_kind(pid)
            self.cpu[pid] = max(cpu, self.cpu.get(pid, 0.0))

    def _run(self) -> None:
        while not self._stop.is_set():
            self.sample()
            self._stop.wait(self.period)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()

    def cpu_by_kind(self) -> dict:
        """CPU seconds per kind (every kind in KINDS, 0 if none ran) and "total"."""
        out = {k: 0.0 for k in KINDS}
        for pid, cpu in self.cpu.items():
            out[self.kind[pid]] += cpu
        out["total"] = sum(out[k] for k in KINDS)
        return {k: round(v, 2) for k, v in out.items()}


def per_sim_second(cpu: dict, sim_s: float) -> dict:
    """CPU seconds per simulated second, per kind."""
    return {k: round(v / sim_s, 4) for k, v in cpu.items()} if sim_s > 0 else {}


def main() -> int:
    root = int(sys.argv[1])
    seconds = float(sys.argv[2]) if len(sys.argv) > 2 else 30.0
    sampler = NodeCpuSampler(root).start()
    end = time.monotonic() + seconds
    while time.monotonic() < end and os.path.exists(f"/proc/{root}"):
        time.sleep(0.5)
    sampler.stop()
    for kind, cpu in sampler.cpu_by_kind().items():
        print(f"{kind:18s} {cpu:8.2f} CPU-s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
