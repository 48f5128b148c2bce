"""The smallest distributed ROS system on network-namespace hosts: master, talker and listener apart.

Why: before running a mission across hosts, prove the harness itself: ROS_MASTER_URI / ROS_IP are right
(the listener on one host receives the talker on another), a cut link really stops the traffic, and the
traffic comes back when the link does. Used by the rostest and by ``netns_harness demo``.
"""
from __future__ import annotations

import os
import tempfile
import time
from dataclasses import dataclass, field

from mbzirc_robustness import constants as C
from mbzirc_robustness.netns import NetnsLab, wait_tcp


@dataclass
class DemoResult:
    """Messages received by the listener in each phase, plus what went wrong (empty when all is fine)."""

    before_cut: int = 0
    during_cut: int = 0
    after_restore: int = 0
    resume_s: float | None = None  # wall seconds from the restore to the first message (TCP backoff)
    problems: list[str] = field(default_factory=list)


def count_lines(path: str, needle: str = "hello") -> int:
    """Messages the listener wrote so far (``rostopic echo -p`` prints one line per message)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return sum(1 for line in f if needle in line)
    except FileNotFoundError:
        return 0


def wait_count(path: str, at_least: int, timeout: float) -> int:
    """Wait until the listener has ``at_least`` messages or ``timeout`` s passed; returns the count."""
    deadline = time.monotonic() + timeout
    n = count_lines(path)
    while n < at_least and time.monotonic() < deadline:
        time.sleep(0.25)
        n = count_lines(path)
    return n


def talker_listener(lab: NetnsLab, cut_s: float = 4.0, workdir: str | None = None) -> DemoResult:
    """Master on ``gs``, ``rostopic pub`` on ``uav1``, ``rostopic echo`` on ``uav2``; cut uav1 for ``cut_s``.

    The lab must already have hosts ``gs``, ``uav1`` and ``uav2``.
    """
    res = DemoResult()
    workdir = workdir or tempfile.mkdtemp(prefix="netns_demo_")
    echo_log = os.path.join(workdir, "listener.log")
    gs_ip = lab.hosts[C.GROUND_STATION].ip
    lab.popen(C.GROUND_STATION, ["roscore", "-p", str(C.MASTER_PORT)], log_path=os.path.join(workdir, "roscore.log"))
    # roscore takes 10-40 s to open its port under a load average of 50-70 (seen in make test)
    if not wait_tcp(lab, "uav1", gs_ip, C.MASTER_PORT, timeout=90):
        res.problems.append("the master on gs is not reachable from uav1 (90 s)")
        return res
    time.sleep(1.0)  # rosout and the parameter server come up just after the port opens
    lab.popen("uav2", ["rostopic", "echo", "-p", "/chatter"], log_path=echo_log)
    lab.popen("uav1", ["rostopic", "pub", "-r", "10", "/chatter", "std_msgs/String", "data: hello"],
              log_path=os.path.join(workdir, "talker.log"))
    res.before_cut = wait_count(echo_log, 5, timeout=30)
    if res.before_cut < 5:
        res.problems.append(f"listener on uav2 got {res.before_cut} messages from uav1 before the cut")
        return res
    lab.cut("uav1")
    time.sleep(0.5)  # messages already in flight may still arrive
    start = count_lines(echo_log)
    time.sleep(cut_s)
    res.during_cut = count_lines(echo_log) - start
    if res.during_cut > 0:
        res.problems.append(f"{res.during_cut} messages crossed a cut link")
    lab.set_link("uav1", True)
    t_restore = time.monotonic()
    back = count_lines(echo_log)
    if wait_count(echo_log, back + 1, timeout=max(30.0, 3 * cut_s)) > back:
        res.resume_s = round(time.monotonic() - t_restore, 2)
    res.after_restore = wait_count(echo_log, back + 5, timeout=10) - back
    if res.after_restore < 5:
        res.problems.append(f"only {res.after_restore} messages after the link came back")
    return res
