#!/usr/bin/env python3
"""Benchmark of the hector_mapping node as `roslaunch` starts it: CPU per scan on the fast-turning flight.

Starts `roslaunch mbzirc_launchers c3_slam.launch` (the thesis's parameters) on a private master, replays
hector_mapping/test/data/floor1_fast.bag (ual_sim's tower first floor, 1 m/s while turning at 1 rad/s,
720-beam laser at 15 Hz) at the bag's own pace (real time, as the laser delivers it: between two scans
the node is idle, which is where OpenBLAS's worker threads spin), never sooner than the node answered the
previous scan (so that none is dropped on a loaded machine), and reads the node's CPU (user + system, every
thread) from /proc before the first and after the last scan. Nothing is set in the node's environment:
the figure is what a user gets.
For comparison, the same replay with OPENBLAS_NUM_THREADS set to the number of cores in the shell (the
OpenBLAS default, what the node ran with before it asked for one thread itself).
    python bench/bench_hector_node.py [--runs 1]
Writes bench/results/hector_node.json. Target (issue 22): <= 10 CPU-ms per scan as launched.
"""
from __future__ import annotations

import argparse
import os
import signal
import socket
import statistics
import subprocess
import sys
import time

from _common import SRC, load_averages, write_result, stop_launch
from _node_cpu import process_stat, descendants, node_kind

BAG = os.path.join(SRC, "hector_mapping", "test", "data", "floor1_fast.bag")
NS = "mbzirc2020_1"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


class Replayer:
    """A node on the private master that plays the bag into hector_mapping in lock-step."""

    def __init__(self):
        import rosbag
        import rospy
        from geometry_msgs.msg import PoseStamped
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan
        from tf2_msgs.msg import TFMessage
        self.rospy, self.Clock, self.TFMessage = rospy, Clock, TFMessage
        rospy.init_node("bench_hector_replay", disable_signals=True)
        self.msgs = list(rosbag.Bag(BAG).read_messages())
        self.clock_pub = rospy.Publisher("/clock", Clock, queue_size=10)
        self.tf_pub = rospy.Publisher("/tf", TFMessage, queue_size=100)
        self.static_pub = rospy.Publisher("/tf_static", TFMessage, queue_size=10, latch=True)
        self.scan_pub = rospy.Publisher(f"/{NS}/scan", LaserScan, queue_size=10)
        self.answered = set()
        rospy.Subscriber(f"/{NS}/slam_out_pose", PoseStamped,
                         lambda m: self.answered.add(round(m.header.stamp.to_sec(), 3)), queue_size=1000)

    def play(self, node_pid: int) -> dict:
        """Replays the bag; CPU seconds of node_pid over the scans, scans sent and answered."""
        rospy, msgs = self.rospy, self.msgs
        self.answered.clear()
        deadline = time.time() + 60.0
        while self.scan_pub.get_num_connections() == 0 and time.time() < deadline:
            self.clock_pub.publish(self.Clock(msgs[0][2]))
            time.sleep(0.1)
        statics = [t for topic, m, _ in msgs if topic == "/tf_static" for t in m.transforms]
        self.static_pub.publish(self.TFMessage(statics))
        self.clock_pub.publish(self.Clock(msgs[0][2]))
        time.sleep(1.0)                                   # the node's TF listener gets the mount
        cpu0, wall0, scans = process_stat(node_pid)[1], time.perf_counter(), 0
        t0 = msgs[0][2].to_sec()
        for topic, m, t in msgs:
            ahead = (t.to_sec() - t0) - (time.perf_counter() - wall0)
            if ahead > 0:
                time.sleep(ahead)
            self.clock_pub.publish(self.Clock(t))
            if topic == "/tf":
                self.tf_pub.publish(m)
            elif topic.endswith("/scan"):
                key = round(m.header.stamp.to_sec(), 3)
                self.scan_pub.publish(m)
                scans += 1
                until = time.time() + 2.0
                while key not in self.answered and time.time() < until:
                    time.sleep(0.001)
        cpu = process_stat(node_pid)[1] - cpu0
        return {"scans": scans, "answered": len(self.answered), "cpu_s": cpu,
                "wall_s": time.perf_counter() - wall0}


def hector_pid(launch: subprocess.Popen, timeout: float = 60.0) -> int:
    end = time.time() + timeout
    while time.time() < end:
        for pid in descendants(launch.pid):
            if node_kind(pid) == "hector_mapping":
                return pid
        time.sleep(0.2)
    raise RuntimeError("hector_mapping did not start")


def run_case(replayer: Replayer, port: int, env: dict) -> dict:
    launch = subprocess.Popen(["roslaunch", "-p", str(port), "mbzirc_launchers", "c3_slam.launch"], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        pid = hector_pid(launch)
        res = replayer.play(pid)
        with open(f"/proc/{pid}/status") as f:
            res["threads"] = int(next(line.split()[1] for line in f if line.startswith("Threads:")))
    finally:
        stop_launch(launch, 20)
    res["cpu_ms_per_scan"] = round(1e3 * res["cpu_s"] / max(res["answered"], 1), 2)
    return res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=1, help="replays of each case (alternating)")
    args = ap.parse_args()
    port = free_port()
    os.environ["ROS_MASTER_URI"] = f"http://localhost:{port}"
    os.environ.setdefault("ROS_HOSTNAME", "localhost")
    user_env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    cases = {"as_launched": user_env,
             "openblas_default_threads": dict(user_env, OPENBLAS_NUM_THREADS=str(os.cpu_count()))}
    core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    try:
        import rosgraph
        master = rosgraph.Master("/bench_hector_node")
        end = time.time() + 30.0
        while not master.is_online() and time.time() < end:
            time.sleep(0.2)
        master.setParam("/use_sim_time", True)
        replayer = Replayer()
        runs = {name: [] for name in cases}
        for _ in range(args.runs):
            for name, env in cases.items():
                r = run_case(replayer, port, env)
                runs[name].append(r)
                print(f"  {name:26s} {r['cpu_ms_per_scan']:7.2f} CPU-ms per scan ({r['answered']}/{r['scans']} "
                      f"scans answered, {r['threads']} threads, {r['wall_s']:.1f} s wall)", flush=True)
    finally:
        core.send_signal(signal.SIGINT)
        core.wait(20)
    res = {name: {"cpu_ms_per_scan": round(statistics.median(r["cpu_ms_per_scan"] for r in rs), 2),
                  "runs": rs} for name, rs in runs.items()}
    res["ratio_default_threads_to_launched"] = round(res["openblas_default_threads"]["cpu_ms_per_scan"]
                                                     / res["as_launched"]["cpu_ms_per_scan"], 2)
    res["target_cpu_ms_per_scan"] = 10.0
    res["load_average"] = load_averages()
    print(f"hector_mapping as launched: {res['as_launched']['cpu_ms_per_scan']} CPU-ms per 720-beam scan "
          f"(target <= 10); with OpenBLAS's default threads {res['openblas_default_threads']['cpu_ms_per_scan']} "
          f"({res['ratio_default_threads_to_launched']}x); load {res['load_average']}")
    write_result("hector_node", res)
    return 0


if __name__ == "__main__":
    sys.exit(main())
