#!/usr/bin/env python3
"""Benchmark of ual_sim: real-time factor reached and CPU time per sensor frame.

Part A (no ROS): CPU time per frame of each sensor model (laser 720 beams, thermal FORWARD / DOWNWARD
32 x 32, RGB-D 640 x 480) at poses near the building, and of one physics tick for 4 and 51 robots.
Part B (ROS, in its own network namespace with its own roscore): the simulator node run as fast as it can
(`~rtf` 0) while this process subscribes to
  1. every laser and thermal camera of 3 UAVs + the UGV (target: >= 10x real time),
  2. the same plus one RGB-D camera (colour + depth, 640 x 480 at 15 Hz) (target: >= 3x),
  3. sensors off, a subscriber on every UAV's `ual/pose`, 50 UAVs and more (target: real time with 50);
     the largest fleet tested that still reaches 1x is reported.
The factor is sim seconds per wall second from the simulator's `/sim/rtf`, averaged over the window; message
counts per sim second prove that the subscribed streams really flow. Writes bench/results/ual_sim.json.
    python bench/bench_ual_sim.py [--window 8] [--fleets 50,100,150]
"""
from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time

from _common import RESULTS, load_average_1min, load_averages, write_result


# ---------------------------------------------------------------------------------------- part A
def cpu_per_frame() -> dict:
    import numpy as np
    from ual_sim.fires import FireSet
    from ual_sim.rgbd import RGBDCamera
    from ual_sim.sim import Simulation
    from ual_sim.thermal import DOWNWARD, FORWARD, ThermalCamera
    from ual_sim.world import load_world

    w = load_world()
    fires = FireSet(w, 1)
    rng = np.random.default_rng(0)
    poses = [(np.array([8.4, 9.5, 6.0]), 0.0), (np.array([14.0, 10.0, 2.0]), 0.5),
             (np.array([12.4, 22.5, 6.5]), -math.pi / 2), (np.array([0.0, 5.0, 3.0]), 0.6),
             (np.array([26.0, 12.0, 9.0]), math.pi)]

    def per_frame(fn, n=40):
        t0 = time.process_time()
        for i in range(n):
            fn(*poses[i % len(poses)])
        return 1e3 * (time.process_time() - t0) / n

    fwd, down, cam = ThermalCamera(FORWARD), ThermalCamera(DOWNWARD), RGBDCamera()
    out = {
        "laser_ms": per_frame(lambda p, y: w.laser_scan(p[0], p[1], p[2], y), 200),
        "thermal_forward_ms": per_frame(lambda p, y: fwd.render(w, fires, p, y, rng), 200),
        "thermal_downward_ms": per_frame(lambda p, y: down.render(w, fires, p, y, rng), 200),
        "rgbd_ms": per_frame(lambda p, y: cam.render(w, fires, p, y), 30),
    }
    for n in (3, 50):
        sim = Simulation(load_world(n_uavs=n), seed=1)
        for r in sim.robots.values():
            r.take_off(3.0) if r.is_uav else None
        t0 = time.process_time()
        for _ in range(300):
            sim.step(1.0 / 30.0)
        out[f"physics_tick_{n + 1}_robots_ms"] = 1e3 * (time.process_time() - t0) / 300
    return {k: round(v, 3) for k, v in out.items()}


# ---------------------------------------------------------------------------------------- part B
class Scenario:
    """One run of the node with a set of subscriptions; returns the factor reached and message rates."""

    def __init__(self, name: str, params: dict, window: float):
        self.name, self.params, self.window = name, params, window

    def run(self, topics: list, setup=None) -> dict:
        import rospy
        args = [f"_{k}:={json.dumps(v) if isinstance(v, bool) else v}" for k, v in self.params.items()]
        node = subprocess.Popen(["rosrun", "ual_sim", "ual_sim_node", "__name:=ual_sim"] + args,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            from std_msgs.msg import Float32
            rospy.wait_for_message("/sim/rtf", Float32, timeout=60)
            if setup:
                setup()
            counts = {t: 0 for t, _ in topics}
            subs = []
            for t, typ in topics:
                def cb(_m, t=t):
                    counts[t] += 1
                # a large buff_size, as any image consumer should use with rospy (the 64 KB default makes
                # rospy read a 1 MB image in many slow chunks)
                subs.append(rospy.Subscriber(t, typ, cb, queue_size=10, buff_size=1 << 24))
            rtfs = []
            sub_rtf = rospy.Subscriber("/sim/rtf", Float32, lambda m: rtfs.append(m.data), queue_size=10)
            deadline = time.time() + 30.0   # every connection up (slow on a loaded machine), then steady state
            while time.time() < deadline and not all(counts.values()):
                time.sleep(0.2)
            time.sleep(2.0)
            rtfs.clear()
            for t in counts:
                counts[t] = 0
            t0 = time.time()
            time.sleep(self.window)
            wall = time.time() - t0
            got = dict(counts)
            for s in subs + [sub_rtf]:
                s.unregister()
            factor = sum(rtfs) / len(rtfs) if rtfs else 0.0
            sim_s = factor * wall
            per_topic = {t: round(n / sim_s, 2) if sim_s > 0 else 0.0 for t, n in got.items()}
            rates = sorted(per_topic.values())
            return {"rtf": round(factor, 2), "window_wall_s": round(wall, 1), "topics": len(topics),
                    "load_average_1min": load_average_1min(),
                    "min_rate_per_sim_s": rates[0] if rates else None,
                    "slowest_topic": min(per_topic, key=per_topic.get) if per_topic else None,
                    "max_rate_per_sim_s": rates[-1] if rates else None}
        finally:
            node.terminate()
            try:
                node.wait(10)
            except subprocess.TimeoutExpired:
                node.kill()
            time.sleep(1.0)


def position_robots(n_uavs: int) -> None:
    """Fly the 3 UAVs near the building (sensors then see walls, fires, interiors) and send the UGV to the door."""
    import rospy
    from geometry_msgs.msg import PoseStamped
    from uav_abstraction_layer.srv import GoToWaypoint, TakeOff
    goals = {1: (-5.0, 16.0, 3.0, 0.0), 2: (8.4, 9.5, 6.0, 0.0), 3: (12.4, 22.5, 6.5, -math.pi / 2),
             0: (14.25, 4.0, 0.0, math.pi / 2)}
    for rid, (x, y, z, yaw) in goals.items():
        if rid > n_uavs:
            continue
        ns = f"/mbzirc2020_{rid}/ual/"
        rospy.wait_for_service(ns + "go_to_waypoint", timeout=30)
        if rid != 0:
            rospy.ServiceProxy(ns + "take_off", TakeOff)(z, True)
        p = PoseStamped()
        p.header.frame_id = "arena"
        p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, z
        p.pose.orientation.z, p.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        rospy.ServiceProxy(ns + "go_to_waypoint", GoToWaypoint)(p, True)


def ros_part(window: float, fleets: list, only: str = "") -> dict:
    import rospy
    from geometry_msgs.msg import PoseStamped
    from sensor_msgs.msg import Image, LaserScan
    from std_msgs.msg import Float64MultiArray
    rospy.init_node("bench_ual_sim", disable_signals=True)
    out = {}
    base = {"uavs": 3, "ugv": True, "seed": 1, "rtf": 0, "wind": True, "markers": False}
    sensors = []
    for rid in (0, 1, 2, 3):
        sensors += [(f"/mbzirc2020_{rid}/scan", LaserScan),
                    (f"/mbzirc2020_{rid}/teraranger_evo_thermal/raw_temp_array", Float64MultiArray)]
    if only in ("", "lasers"):
        out["lasers_thermals"] = Scenario("lasers_thermals", base, window).run(sensors, lambda: position_robots(3))
        print(f"  3 UAVs + UGV, every laser and thermal subscribed: {out['lasers_thermals']}", flush=True)
    rgbd = sensors + [("/mbzirc2020_2/camera/color/image_rect_color", Image),
                      ("/mbzirc2020_2/camera/aligned_depth_to_color/image_raw", Image)]
    if only in ("", "rgbd"):
        out["lasers_thermals_rgbd"] = Scenario("rgbd", base, window).run(rgbd, lambda: position_robots(3))
        print(f"  ... plus one RGB-D 640x480 at 15 Hz: {out['lasers_thermals_rgbd']}", flush=True)
    fleet = {}
    for n in (fleets if only in ("", "fleet") else []):
        prm = {"uavs": n, "ugv": False, "seed": 1, "rtf": 0, "laser": False, "thermal": False, "rgbd": False,
               "markers": False, "wind": False}
        poses = [(f"/mbzirc2020_{i}/ual/pose", PoseStamped) for i in range(1, n + 1)]
        fleet[n] = Scenario(f"fleet_{n}", prm, window).run(poses)
        print(f"  {n} UAVs, sensors off, every pose subscribed: {fleet[n]}", flush=True)
        if fleet[n]["rtf"] < 1.0:
            break
    out["fleet"] = {str(k): v for k, v in fleet.items()}
    ok = [n for n, v in fleet.items() if v["rtf"] >= 1.0]
    out["largest_fleet_real_time"] = max(ok) if ok else 0
    return out


def isolated_main(args) -> int:
    """Runs inside a fresh network namespace: own roscore on the default port, nobody else to disturb."""
    port = 11311
    os.environ["ROS_MASTER_URI"] = f"http://localhost:{port}"
    core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 60.0   # the master may take a while on a loaded machine
        while subprocess.run(["rosparam", "set", "/use_sim_time", "true"], stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL).returncode != 0:
            if time.time() > deadline:
                raise RuntimeError("roscore did not come up within 60 s")
            time.sleep(1.0)
        ros = ros_part(args.window, [int(x) for x in args.fleets.split(",") if x], args.only)
    finally:
        core.terminate()
        core.wait(20)
    with open(args.partial, "w") as f:
        json.dump(ros, f)
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--window", type=float, default=8.0, help="wall seconds measured per scenario")
    ap.add_argument("--fleets", default="50,100,150", help="fleet sizes tried, ascending")
    ap.add_argument("--only", default="", choices=["", "lasers", "rgbd", "fleet"], help="run one scenario")
    ap.add_argument("--isolated", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--partial", default=os.path.join(RESULTS, ".ual_sim_ros.json"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.isolated:
        return isolated_main(args)
    os.makedirs(RESULTS, exist_ok=True)
    print("CPU time per frame (ms, in-process):", flush=True)
    cpu = cpu_per_frame()
    for k, v in cpu.items():
        print(f"  {k}: {v}")
    cmd = [sys.executable, os.path.abspath(__file__), "--isolated", "--window", str(args.window),
           "--fleets", args.fleets, "--partial", args.partial, "--only", args.only]
    if shutil.which("unshare") and subprocess.run(["unshare", "-n", "true"]).returncode == 0:
        cmd = ["unshare", "-n", "sh", "-c", 'ip link set lo up; exec "$@"', "sh"] + cmd
    else:
        print("warning: no network namespace available; using port 11311 of this machine", flush=True)
    print("ROS node runs (rtf 0 = as fast as possible):", flush=True)
    rc = subprocess.run(cmd).returncode
    ros = {}
    if rc == 0 and os.path.exists(args.partial):
        with open(args.partial) as f:
            ros = json.load(f)
        os.remove(args.partial)
    result = {"cpu_ms_per_frame": cpu, **ros, "load_average_1_5_15": load_averages(),
              "targets": {"lasers_thermals_rtf": 10.0, "with_rgbd_rtf": 3.0, "fleet_real_time": 50}}
    if ros and not args.only:
        result["meets"] = {"lasers_thermals": ros["lasers_thermals"]["rtf"] >= 10.0,
                           "with_rgbd": ros["lasers_thermals_rgbd"]["rtf"] >= 3.0,
                           "fleet_50": ros["largest_fleet_real_time"] >= 50}
    if not args.only:   # a partial run does not overwrite the benchmark's result
        write_result("ual_sim", result)
    print(json.dumps(result.get("meets", {})))
    return rc


if __name__ == "__main__":
    sys.exit(main())
