#!/usr/bin/env python3
"""Replay one robot of a recorded trial's slam.bag (tools/run_mission.sh RECORD_SLAM=1) through the indoor pose
offline, with the code of the working tree, and print its log and its pose error against the truth.

    python bench/replay_slam_bag.py results/<trial>/slam.bag 2 [--from 240] [--to 380] [--every 0.5]

The node's wiring (node.py) without ROS: ual/pose, ual/gnss_status and slam_out_pose in the order they were
recorded, the scans for the outline refinement, the mapping gate every 0.2 s. The SLAM poses are the
recorded ones: the replay is faithful while the code replayed asks hector_mapping for new maps when the
recorded run did (a map asked for that never came shows as a jump not seen, one not asked for as a jump).
The truth (/sim/robots, the referee's, 2 Hz) is read for the error only: at each of its samples, the
poses interpolated (as the referee scores a flight). Default params
(README); the world: the arena model (a public outline: every floor plan of ual_sim has the same).
"""
import argparse
import bisect
import math
import sys

import rosbag

from indoor_localization.anchor import IndoorPose, Params
from indoor_localization.mapping_gate import MappingGate
from indoor_localization.outline import RefineParams
from indoor_localization.refinement import OutlineRefinement
from mbzirc_arena.c3 import ARENA
from mbzirc_arena.yaw import yaw_from_quaternion

GATE_PERIOD = 0.2            # s, the node's SOURCE_CHECK_PERIOD
MAX_POSE_GAP = 0.25          # s: a truth sample between poses further apart is not scored (the referee's rule)


def yaw_of(q) -> float:
    yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
    return math.nan if yaw is None else yaw       # a bad orientation: the core drops the pose, saying why


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("bag")
    ap.add_argument("robot", type=int)
    ap.add_argument("--from", dest="t0", type=float, default=-math.inf, help="print from this sim time (s)")
    ap.add_argument("--to", dest="t1", type=float, default=math.inf, help="stop at this sim time (s)")
    ap.add_argument("--every", type=float, default=1.0, help="s between printed pose errors (0: none)")
    ap.add_argument("--outline", action="append", default=[], metavar="NAME=VALUE",
                    help="an ~outline/ param other than its default (repeatable), e.g. window_view=0")
    args = ap.parse_args()
    defaults = RefineParams()
    try:
        refine = RefineParams(**{k: type(getattr(defaults, k))(v) if not isinstance(getattr(defaults, k), bool)
                                 else v.lower() in ("1", "true", "yes")
                                 for k, v in (kv.split("=", 1) for kv in args.outline)})
    except (TypeError, ValueError, AttributeError) as e:
        ap.error(f"--outline: {e}")
    ns = f"/mbzirc2020_{args.robot}/"
    log = lambda level: (lambda m: print(f"{now:10.3f} {level} {m}") if now >= args.t0 else None)  # noqa: E731
    core = IndoorPose(Params(), ARENA.footprints)
    outline = OutlineRefinement(ARENA, refine, info=log("INFO"), warn=log("WARN"))
    gate = MappingGate(ARENA.footprints)
    truth_t, truth_xy = [], []       # /sim/robots: the robot's true x, y and their stamps
    poses, flight = [], None           # (t, x, y, source) per pose without GNSS; the flight's start
    flights = []
    now, next_gate, next_print = -math.inf, -math.inf, -math.inf
    topics = ["/sim/robots"] + [ns + k for k in ("ual/pose", "ual/gnss_status", "slam_out_pose", "scan")]
    for topic, m, t in rosbag.Bag(args.bag).read_messages(topics=topics):
        now = t.to_sec()
        if now > args.t1:
            break
        if topic == "/sim/robots":
            if args.robot < len(m.poses):
                p = m.poses[args.robot].position
                truth_t.append(m.header.stamp.to_sec())
                truth_xy.append((p.x, p.y))
            continue
        name = topic[len(ns):]
        if name == "scan":
            outline.on_scan(m)
        elif name == "ual/pose":
            p = m.pose.position
            core.on_reported(m.header.stamp.to_sec(), p.x, p.y, p.z, yaw_of(m.pose.orientation))
        elif name == "ual/gnss_status":
            was = core.gnss_valid
            core.on_gnss(now, m.status >= 0)
            if was and not core.gnss_valid:
                flight = now
            elif core.gnss_valid and not was and flight is not None:
                flights.append((flight, now))
                flight = None
        elif name == "slam_out_pose":
            p, ts = m.pose.position, m.header.stamp.to_sec()
            yaw = yaw_of(m.pose.orientation)
            out = core.on_slam(ts, p.x, p.y, yaw)
            if out is not None:
                outline.update(core, ts, (p.x, p.y, yaw), out.z)
            core.take_reset_request()
            if out is not None and not core.gnss_valid:
                poses.append((ts, out.x, out.y, out.source))
        for e in core.pop_events():
            log("INFO")(f"indoor_pose: {e}")
        if now >= next_gate:
            next_gate = now + GATE_PERIOD
            last = core.reported.latest()
            if last is not None and gate.update(core.gnss_valid, last[1], last[2]):
                core.expect_new_map()
    if flight is not None:
        flights.append((flight, now))
    # at each truth sample (the referee's way: its 2 Hz samples are exact, the 15 Hz poses interpolated)
    errors = []                        # (t, error) at the truth's samples without GNSS
    pt = [q[0] for q in poses]
    for t, (tx, ty) in zip(truth_t, truth_xy):
        i = bisect.bisect_left(pt, t)
        if i == 0 or i >= len(poses) or poses[i][0] - poses[i - 1][0] > MAX_POSE_GAP:
            continue
        a, b = poses[i - 1], poses[i]
        w = (t - a[0]) / (b[0] - a[0])
        x, y = a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2])
        e = math.hypot(x - tx, y - ty)
        errors.append((t, e))
        if args.every > 0 and t >= max(args.t0, next_print):
            next_print = t + args.every
            print(f"{t:10.3f} POSE ({x:6.2f}, {y:6.2f}) truth ({tx:6.2f}, {ty:6.2f}) "
                  f"error ({x - tx:+.3f}, {y - ty:+.3f}) |{e:.3f}| {b[3]}")
    print(f"\nrobot {args.robot}: {len(flights)} period(s) without GNSS")
    for a, b in flights:
        es = [e for ts, e in errors if a <= ts <= b]
        if es:
            rms = math.sqrt(sum(e * e for e in es) / len(es))
            print(f"  {a:8.2f}-{b:8.2f} s: {len(es)} truth samples, RMS {rms:.3f} m, max {max(es):.3f} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
