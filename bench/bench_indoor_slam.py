#!/usr/bin/env python3
"""SLAM in the loop (issue 18): one UAV flies in through a window, around a floor of the tower and out again
with no GNSS indoors, navigating indoors on its anchored SLAM pose; figures of the pose error and the CPU.

Starts on a private master, as `roslaunch` starts them (nothing set in their environment): ual_sim with two
UAVs (UAV 2 flies; thermal and RGB-D off), `gnss_denied_indoors:=true`, the lasers at 15 Hz, and
`mbzirc_launchers/launch/indoor_slam.launch id:=2` (hector_mapping with the thesis's parameters +
indoor_pose). The script is UAV 2's pilot: outdoors it commands waypoints in the UAL's (GNSS) frame; once
`localization/source` says `slam` it corrects every waypoint by the offset between the UAL's dead-reckoned
pose and the anchored SLAM pose (the UAL holds its drifting frame, so a robot that trusted it would leave
its path), and it hovers while the source is `none` (fails after 5 s). The path: take-off at home, in
front of facade C's first-floor window (hover 3 s: the anchor is fitted there), in at 7.5 m, down to 6.2 m
(the doorways end at 7.2 m), through the west room, the doorway of the interior wall into the east room,
around it, back, through the other doorway into the north room, around it, up to 7.5 m and out.

Figures: the anchored pose (`localization/pose`) against the truth (`/sim/robots`, the referee's; tests may
read it) while the source is `slam`: RMS and max horizontal error, the same minus the GNSS error at the
window (the mean error of the reported pose over the anchor's 3 s before the loss, at the truth's 2 Hz:
the anchor inherits it; under `ideal` GNSS there is none), the error's spread about its indoor mean (the
SLAM's own drift and noise), heading error; hector's CPU
per scan (its process's CPU over the flight / scans answered) and per simulated second; indoor_pose's and
ual_sim's CPU per simulated second; the scans' rate and beam count as received.
    python bench/bench_indoor_slam.py [--uncertainty ideal|realistic] [--rtf 2] [--seed 1] [--no-outline]
Writes bench/results/indoor_slam_<uncertainty>.json (`--no-outline`: indoor_pose without its refinement
by the building outline, the anchor as GNSS left it; written to indoor_slam_<uncertainty>_no_outline.json).

What it costs the mission, side by side in one run: the same seed's trial (tools/run_mission.sh, every node)
without and with `INDOOR_SLAM=1` (hector_mapping + indoor_pose on the UGV and both water UAVs, lasers at
15 Hz), the CPU per simulated second of each node kind sampled from /proc (bench_mission.py's sampler):
    python bench/bench_indoor_slam.py --mission-seed 1 --rtf 4 [--mission-duration 400]
Writes bench/results/indoor_slam_mission.json.
"""
from __future__ import annotations

import argparse
import math
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections import deque

from _common import load_averages, write_result, stop_launch
from _node_cpu import KINDS, descendants, node_kind, process_stat

NS = "mbzirc2020_2"
WINDOW_Z, FLOOR_Z = 7.5, 6.2
# (x, y, z, yaw, hover s): facade C (x = 11.4) first-floor window y 11.5-13.5, z 6.5-8.5; interior wall
# x 17.7-17.9 with a doorway at y 10-12 (z 5-7.2), wall y 15-15.2 with a doorway at x 13.5-15.5
PATH = [(6.0, 12.5, WINDOW_Z, 0.0, 0.0), (9.5, 12.5, WINDOW_Z, 0.0, 3.0),
        (13.0, 12.5, WINDOW_Z, 0.0, 0.0), (14.5, 12.0, FLOOR_Z, 0.0, 0.0), (16.2, 11.0, FLOOR_Z, 0.0, 0.0),
        (19.5, 11.0, FLOOR_Z, 0.0, 0.0), (22.0, 11.0, FLOOR_Z, math.pi / 2, 0.0),
        (22.0, 17.5, FLOOR_Z, math.pi, 0.0), (20.0, 17.5, FLOOR_Z, -math.pi / 2, 0.0),
        (20.5, 8.5, FLOOR_Z, math.pi, 0.0), (19.5, 11.0, FLOOR_Z, math.pi, 0.0),
        (16.2, 11.0, FLOOR_Z, math.pi / 2, 0.0), (14.5, 13.5, FLOOR_Z, math.pi / 2, 0.0),
        (14.5, 17.2, FLOOR_Z, math.pi, 0.0), (12.6, 17.4, FLOOR_Z, 0.0, 0.0), (16.6, 17.4, FLOOR_Z, -math.pi / 2, 0.0),
        (14.5, 16.8, FLOOR_Z, -math.pi / 2, 0.0), (14.5, 13.0, FLOOR_Z, math.pi, 0.0),
        (13.0, 12.5, WINDOW_Z, math.pi, 0.0), (9.0, 12.5, WINDOW_Z, math.pi, 0.0), (6.0, 12.5, WINDOW_Z, math.pi, 2.0)]
REACHED_XY, REACHED_YAW = 0.15, 0.1
LAUNCH = """<launch>
  <include file="$(find ual_sim)/launch/c3_world.launch">
    <arg name="uavs" value="2"/> <arg name="ugv" value="false"/> <arg name="seed" value="{seed}"/>
    <arg name="rtf" value="{rtf}"/> <arg name="thermal" value="false"/> <arg name="rgbd" value="false"/>
    <arg name="uncertainty" value="{uncertainty}"/> <arg name="gnss_denied_indoors" value="true"/>
    <arg name="laser_rate" value="15"/> <arg name="output" value="log"/>
  </include>
  <include file="$(find mbzirc_launchers)/launch/indoor_slam.launch"><arg name="id" value="2"/>
    <arg name="outline_refinement" value="{outline}"/></include>
</launch>
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def yaw_of(q) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def pid_of(root: int, kind: str, timeout: float = 60.0) -> int:
    """The process of a node kind (_node_cpu.py's) under root."""
    end = time.time() + timeout
    while time.time() < end:
        for pid in descendants(root):
            if node_kind(pid) == kind:
                return pid
        time.sleep(0.2)
    raise RuntimeError(f"{kind} did not start")


class Pilot:
    """UAV 2's pilot and the figures' recorder (a node on the private master, sim time)."""

    def __init__(self):
        import rospy
        from geometry_msgs.msg import PoseArray, PoseStamped
        from sensor_msgs.msg import LaserScan, NavSatStatus
        from std_msgs.msg import String
        self.rospy, self.PoseStamped = rospy, PoseStamped
        rospy.init_node("bench_indoor_slam_pilot", disable_signals=True)
        self.lock = threading.Lock()
        self.ual = deque(maxlen=120)           # (t, x, y, z, yaw) reported
        self.loc = deque(maxlen=60)            # (t, x, y, z, yaw) anchored
        self.source = "gnss"
        self.gnss = True
        self.all = {"ual": [], "loc": [], "truth": []}   # every row, evaluated after the flight
        self.gnss_changes = []                 # (sim time, valid) as ual/gnss_status said
        self.scans = []                        # (t, beams)
        self.slam_poses = 0
        self.sp = rospy.Publisher(f"/{NS}/ual/set_pose", PoseStamped, queue_size=1)
        rospy.Subscriber(f"/{NS}/ual/pose", PoseStamped, self.on_ual, queue_size=10)
        rospy.Subscriber(f"/{NS}/localization/pose", PoseStamped, self.on_loc, queue_size=10)
        rospy.Subscriber(f"/{NS}/localization/source", String, self.on_source, queue_size=10)
        rospy.Subscriber(f"/{NS}/ual/gnss_status", NavSatStatus, self.on_gnss, queue_size=10)
        rospy.Subscriber("/sim/robots", PoseArray, self.on_truth, queue_size=10)
        rospy.Subscriber(f"/{NS}/scan", LaserScan, self.on_scan, queue_size=10)
        rospy.Subscriber(f"/{NS}/slam_out_pose", PoseStamped, self.on_slam, queue_size=10)
        self.index = None

    # ---------------------------------------------------------------- callbacks
    @staticmethod
    def _row(m):
        p = m.pose.position
        return m.header.stamp.to_sec(), p.x, p.y, p.z, yaw_of(m.pose.orientation)

    def on_ual(self, m):
        with self.lock:
            self.ual.append(self._row(m))
            self.all["ual"].append(self.ual[-1])

    def on_loc(self, m):
        with self.lock:
            self.loc.append(self._row(m))
            self.all["loc"].append(self.loc[-1])

    def on_source(self, m):
        with self.lock:
            self.source = m.data

    def on_gnss(self, m):
        with self.lock:
            valid = m.status >= 0
            if valid != self.gnss:
                self.gnss_changes.append((self.rospy.get_time(), valid))
            self.gnss = valid

    def on_slam(self, _m):
        self.slam_poses += 1

    def on_scan(self, m):
        with self.lock:
            self.scans.append((m.header.stamp.to_sec(), len(m.ranges)))

    def on_truth(self, m):
        if self.index is None:
            ids = self.rospy.get_param("/sim/robot_ids", [1, 2])
            self.index = ids.index(2)
        p = m.poses[self.index]
        with self.lock:
            self.all["truth"].append((m.header.stamp.to_sec(), p.position.x, p.position.y, p.position.z,
                                      yaw_of(p.orientation)))

    def indoor_errors(self):
        """[(t, dx, dy, dyaw, (GNSS error x, y over the anchor window before the loss))] of the anchored
        pose against the truth at every truth sample while the fix was lost, and the GNSS errors at the
        losses (the reported pose's error then, which the anchor inherits)."""
        rows, losses, lost_since, err_at_loss = [], [], None, (0.0, 0.0)
        changes = list(self.gnss_changes)
        for t, x, y, _, yaw in self.all["truth"]:
            while changes and changes[0][0] <= t:
                ct, valid = changes.pop(0)
                lost_since = None if valid else ct
                if not valid:     # mean error of the reported pose over the anchor's window (3 s)
                    errs = [(rep[0] - r[1], rep[1] - r[2]) for r in self.all["truth"] if ct - 3.2 <= r[0] < ct - 0.2
                            for rep in [interpolate(self.all["ual"], r[0])] if rep is not None]
                    err_at_loss = tuple(sum(e[i] for e in errs) / len(errs) for i in (0, 1)) if errs else (0.0, 0.0)
                    losses.append(err_at_loss)
            if lost_since is None or t < lost_since + 0.5:    # the source switches on the status message
                continue
            est = interpolate(self.all["loc"], t)
            if est is not None:
                rows.append((t, est[0] - x, est[1] - y, wrap(est[3] - yaw), err_at_loss))
        return rows, losses

    # ---------------------------------------------------------------- piloting
    def estimate(self):
        """(x, y, z, yaw) the pilot believes, and the offset (dx, dy) to add to an arena waypoint."""
        with self.lock:
            if not self.ual:
                return None, None
            u = self.ual[-1]
            if self.source == "gnss":
                return u[1:], (0.0, 0.0)
            if self.source != "slam" or not self.loc:
                return None, None
            loc = self.loc[-1]
            rep = next((r for r in reversed(self.ual) if abs(r[0] - loc[0]) < 1e-3), u)
            return loc[1:], (rep[1] - loc[1], rep[2] - loc[2])

    def fly(self, log) -> bool:
        rospy = self.rospy
        from uav_abstraction_layer.srv import TakeOff
        rospy.wait_for_service(f"/{NS}/ual/take_off", 60)
        rospy.ServiceProxy(f"/{NS}/ual/take_off", TakeOff)(height=WINDOW_Z, blocking=True)
        rate = rospy.Rate(10)
        for k, (x, y, z, yaw, hover) in enumerate(PATH):
            start, none_since, reached_at = rospy.get_time(), None, None
            while not rospy.is_shutdown():
                now = rospy.get_time()
                est, off = self.estimate()
                if est is None:
                    none_since = none_since if none_since is not None else now
                    if now - none_since > 5.0:
                        log(f"waypoint {k}: no valid pose for 5 s (source {self.source}); abort")
                        return False
                    rate.sleep()
                    continue
                none_since = None
                m = self.PoseStamped()
                m.header.frame_id = "arena"
                m.pose.position.x, m.pose.position.y, m.pose.position.z = x + off[0], y + off[1], z
                m.pose.orientation.z, m.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
                self.sp.publish(m)
                close = (math.hypot(est[0] - x, est[1] - y) < REACHED_XY and abs(est[2] - z) < 0.2
                         and abs(wrap(est[3] - yaw)) < REACHED_YAW)
                if close and reached_at is None:
                    reached_at = now
                if reached_at is not None and now - reached_at >= hover:
                    break
                if now - start > 40.0:
                    log(f"waypoint {k} ({x}, {y}, {z}) not reached in 40 s (estimate {est}); abort")
                    return False
                rate.sleep()
        return True


def interpolate(rows, t):
    """(x, y, z, yaw) of the rows (t, x, y, z, yaw) at t, linear between the two around it (<= 0.2 s)."""
    prev = None
    for r in rows:
        if r[0] >= t:
            if r[0] == t:
                return r[1:]
            if prev is None or r[0] - prev[0] > 0.2:
                return None
            a = (t - prev[0]) / (r[0] - prev[0])
            return tuple(prev[i] + a * (r[i] - prev[i]) for i in (1, 2, 3)) + (
                wrap(prev[4] + a * wrap(r[4] - prev[4])),)
        prev = r
    return None


def mission_cost(args: argparse.Namespace) -> int:
    """The seed's trial without and with indoor SLAM, CPU per simulated second per node kind."""
    from bench_mission import run_seed
    runs = {}
    with tempfile.TemporaryDirectory(prefix="indoor_slam_mission_") as out_root:
        for slam in (False, True):
            # GNSS indoors in both (without SLAM a robot without it would hold at its window): the cost alone
            ns = argparse.Namespace(uavs=3, rtf=args.rtf, duration=args.mission_duration, uncertainty=args.uncertainty,
                                    indoor_slam="yes" if slam else "no", gnss_denied_indoors="no")
            r = run_seed(args.mission_seed, ns, os.path.join(out_root, "slam" if slam else "base"))
            runs["indoor_slam" if slam else "without"] = {k: r.get(k) for k in (
                "fires_extinguished", "crashes", "sim_time_s", "real_time_factor", "cpu_s_per_sim_s", "error")}
            print(f"  {'with' if slam else 'without':7s} indoor SLAM: {r.get('fires_extinguished')} fires out, "
                  f"{r.get('sim_time_s')} sim s, rtf {r.get('real_time_factor')}, CPU-s per sim s "
                  f"{r.get('cpu_s_per_sim_s')}", flush=True)
    a, b = runs["without"]["cpu_s_per_sim_s"] or {}, runs["indoor_slam"]["cpu_s_per_sim_s"] or {}
    res = {"seed": args.mission_seed, "rtf_asked": args.rtf, "uncertainty": args.uncertainty, "runs": runs,
           "added_cpu_s_per_sim_s": {k: round(b.get(k, 0.0) - a.get(k, 0.0), 4) for k in KINDS + ("total",)},
           "budget_cpu_s_per_sim_s": 0.35, "load_average": load_averages()}
    print(f"indoor SLAM adds {res['added_cpu_s_per_sim_s'].get('total')} CPU-s per sim s to the mission "
          f"({a.get('total')} -> {b.get('total')}; budget 0.35): {res['added_cpu_s_per_sim_s']}")
    write_result("indoor_slam_mission", res)
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--uncertainty", default="ideal", choices=("ideal", "realistic"))
    ap.add_argument("--rtf", type=float, default=2.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--no-outline", action="store_true", help="indoor_pose without the outline refinement")
    ap.add_argument("--mission-seed", type=int, default=None, help="compare a whole trial without/with SLAM")
    ap.add_argument("--mission-duration", type=float, default=400.0, help="sim s of each trial (same for both)")
    args = ap.parse_args()
    if args.mission_seed is not None:
        return mission_cost(args)
    port = free_port()
    os.environ["ROS_MASTER_URI"] = f"http://localhost:{port}"
    os.environ.setdefault("ROS_HOSTNAME", "localhost")
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    with tempfile.NamedTemporaryFile("w", suffix=".launch", delete=False) as f:
        f.write(LAUNCH.format(seed=args.seed, rtf=args.rtf, uncertainty=args.uncertainty,
                              outline="false" if args.no_outline else "true"))
        launch_file = f.name
    launch = subprocess.Popen(["roslaunch", "-p", str(port), launch_file], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)
    lines = []

    def log(text):
        print(text, flush=True)
        lines.append(text)
    try:
        pids = {k: pid_of(launch.pid, k) for k in ("hector_mapping", "indoor_pose", "ual_sim")}
        pilot = Pilot()
        rospy = pilot.rospy
        while rospy.get_time() == 0.0:
            time.sleep(0.1)
        cpu0 = {k: process_stat(p)[1] for k, p in pids.items()}
        sim0, wall0, slam0 = rospy.get_time(), time.time(), pilot.slam_poses
        ok = pilot.fly(log)
        cpu = {k: process_stat(p)[1] - cpu0[k] for k, p in pids.items()}
        sim_s, wall_s, slam_n = rospy.get_time() - sim0, time.time() - wall0, pilot.slam_poses - slam0
    finally:
        stop_launch(launch, 30)
        os.unlink(launch_file)
    rows, losses = pilot.indoor_errors()
    err = [math.hypot(dx, dy) for _, dx, dy, _, _ in rows]
    err_slam = [math.hypot(dx - b[0], dy - b[1]) for _, dx, dy, _, b in rows]
    mx = sum(r[1] for r in rows) / len(rows) if rows else 0.0
    my = sum(r[2] for r in rows) / len(rows) if rows else 0.0
    rms = lambda v: math.sqrt(sum(x * x for x in v) / len(v)) if v else float("nan")  # noqa: E731
    scans = pilot.scans
    span = scans[-1][0] - scans[0][0] if len(scans) > 1 else float("nan")
    res = {
        "uncertainty": args.uncertainty, "outline_refinement": not args.no_outline, "seed": args.seed, "rtf_asked": args.rtf, "flight_completed": ok,
        "sim_s": round(sim_s, 1), "wall_s": round(wall_s, 1), "indoor_samples": len(rows),
        "gnss_error_at_window_m": [[round(v, 3) for v in e] for e in losses],
        "pose_error_rms_m": round(rms(err), 3), "pose_error_max_m": round(max(err, default=float("nan")), 3),
        "pose_error_minus_gnss_at_window_rms_m": round(rms(err_slam), 3),
        "pose_error_minus_gnss_at_window_max_m": round(max(err_slam, default=float("nan")), 3),
        "pose_error_about_its_mean_max_m": round(max((math.hypot(dx - mx, dy - my) for _, dx, dy, _, _ in rows),
                                                     default=float("nan")), 3) if rows else None,
        "yaw_error_max_rad": round(max((abs(r[3]) for r in rows), default=float("nan")), 4),
        "scan_beams": sorted({b for _, b in scans}), "scan_rate_hz": round((len(scans) - 1) / span, 2),
        "slam_poses": slam_n,
        "hector_cpu_ms_per_scan": round(1e3 * cpu["hector_mapping"] / max(slam_n, 1), 2),
        "cpu_s_per_sim_s": {k: round(v / sim_s, 4) for k, v in cpu.items()},
        "load_average": load_averages(),
        "indoor_error_series": [[round(t, 2), round(math.hypot(dx, dy), 3)] for t, dx, dy, _, _ in rows],
    }
    log(f"indoor SLAM ({args.uncertainty}, outline refinement {'off' if args.no_outline else 'on'}): flight {'completed' if ok else 'ABORTED'} in {res['sim_s']} sim s; "
        f"anchored pose vs truth indoors: RMS {res['pose_error_rms_m']} m, max {res['pose_error_max_m']} m "
        f"({len(rows)} samples); minus the GNSS error at the window {res['gnss_error_at_window_m']}: RMS "
        f"{res['pose_error_minus_gnss_at_window_rms_m']} m, max {res['pose_error_minus_gnss_at_window_max_m']} m; "
        f"about its mean: max {res['pose_error_about_its_mean_max_m']} m; yaw max {res['yaw_error_max_rad']} rad")
    log(f"hector_mapping as launched: {res['hector_cpu_ms_per_scan']} CPU-ms per scan ({slam_n} scans, "
        f"{res['scan_beams']} beams at {res['scan_rate_hz']} Hz); CPU-s per sim s {res['cpu_s_per_sim_s']}; "
        f"load {res['load_average']}")
    write_result(f"indoor_slam_{args.uncertainty}" + ("_no_outline" if args.no_outline else ""), res)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
