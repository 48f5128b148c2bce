#!/usr/bin/env python3
"""Makes window_scans.npz, the recorded scans of the window / door detection tests (test_recorded_openings.py),
from bags of ual_sim runs (the on-demand rostests' `record:=FILE.bag`: mbzirc_central_unit
indoor_gnss_denied.test, a UAV at a window, and mbzirc_agents ugv_gnss_denied.test, the UGV at its door).

Why recorded: the synthetic scans of test_openings.py come from the tests' own ray caster; these are the
simulator's laser (its noise and dropouts, the robot moving and swaying in the wind, other walls and
openings in view) with the truth beside them (/sim/robots and the world file's openings: test-only data,
never the robots').

Kept: scans with the robot outside the building's outline (approaching) or inside it (leaving), 0.8-4.5 m
from an opening of the world at the laser's height, facing it within 25 deg; at most --per-bag of them,
spread evenly over each bag. Stored per scan: ranges (float32), the angles, and the opening's truth in the
laser's frame at that moment (lateral offset of its middle, distance to its wall plane, width) and whether
the robot was inside the building's outline.

Run: python3 make_window_scans.py BAG:ROBOT_INDEX:LASER_Z [...] [--world FILE] [--out window_scans.npz]
(ROBOT_INDEX: the robot's place in /sim/robots, i.e. in /sim/robot_ids; LASER_Z: m of its laser above its base,
0.1 for ual_sim's UAVs, 0.9 for its UGV). The file in the repository: uav_1..3 (indoor_gnss_denied.test, three
runs) and ugv_1 (ugv_gnss_denied.test) with --per-bag 12.
"""
import argparse
import math
import os

import numpy as np
import rosbag
import yaml
from mbzirc_arena.c3 import FOOTPRINTS
from mbzirc_arena.yaw import yaw_from_quaternion


def world_openings(path):
    """[(x0, y0, x1, y1, z0, z1, axis)] of every opening: its span on the wall's outer face line."""
    world = yaml.safe_load(open(path))
    out = []
    for w in world.get('walls', []):
        lo, hi = w['min'], w['max']
        axis = 'x' if hi[0] - lo[0] < hi[1] - lo[1] else 'y'     # the wall runs along y (axis 'x': x const)
        for o in w.get('openings', []):
            a0, a1 = o['along']
            z0, z1 = o['z']
            if axis == 'x':
                out.append((lo[0], a0, hi[0], a1, z0, z1, axis))
            else:
                out.append((a0, lo[1], a1, hi[1], z0, z1, axis))
    return out


def truth(pose, opening):
    """(lateral, distance, width) of the opening in the body frame of pose (x, y, z, yaw), or None when the
    robot does not face it within 25 deg from 0.8-4.5 m or the laser's height is not within it."""
    x, y, z, yaw = pose
    x0, y0, x1, y1, z0, z1, axis = opening
    if not z0 + 0.15 <= z <= z1 - 0.15:     # z: the laser's height; its plane well within the opening
        return None
    if axis == 'x':
        plane = x0 if abs(x - x0) < abs(x - x1) else x1          # the face the robot looks at
        mid, width, normal = np.array([plane, 0.5 * (y0 + y1)]), y1 - y0, np.array([math.copysign(1.0, plane - x), 0.0])
    else:
        plane = y0 if abs(y - y0) < abs(y - y1) else y1
        mid, width, normal = np.array([0.5 * (x0 + x1), plane]), x1 - x0, np.array([0.0, math.copysign(1.0, plane - y)])
    rel = mid - np.array([x, y])
    distance = float(rel @ normal)
    heading = np.array([math.cos(yaw), math.sin(yaw)])
    if not 0.8 <= distance <= 4.5 or math.degrees(math.acos(max(-1.0, min(1.0, heading @ normal)))) > 25.0:
        return None
    c, s = math.cos(yaw), math.sin(yaw)
    lateral = float(-s * rel[0] + c * rel[1])
    if abs(lateral) > 1.5:
        return None
    return lateral, distance, width


def in_footprint(pose, footprint):
    """True inside a building's outline below its roof (x0, y0, x1, y1, top)."""
    x0, y0, x1, y1, top = footprint[:5]
    return x0 <= pose[0] <= x1 and y0 <= pose[1] <= y1 and pose[2] < top


def truth_at(truths, stamp, gap=1.0, max_turn=0.05, max_move=1.0):
    """(x, y, z, yaw) of the robot at stamp, interpolated between the two true poses around it (at most gap
    s apart: /sim/robots comes at a few Hz); None outside them, and while the robot turned more than max_turn
    rad or moved more than max_move m between them (the interpolation would be a guess)."""
    for (t0, *a), (t1, *b) in zip(truths, truths[1:]):
        if t0 <= stamp <= t1 and t1 - t0 <= gap:
            if abs(math.remainder(b[3] - a[3], 2 * math.pi)) > max_turn or math.dist(a[:2], b[:2]) > max_move:
                return None
            w = 0.0 if t1 == t0 else (stamp - t0) / (t1 - t0)
            yaw = a[3] + w * math.remainder(b[3] - a[3], 2 * math.pi)
            return (a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2]), yaw)
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('bags', nargs='+')
    ap.add_argument('--world', default=os.path.join(os.path.dirname(__file__), '..', '..', '..', '..', 'ual_sim',
                                                    'src', 'ual_sim', 'worlds', 'c3_default.yaml'))
    ap.add_argument('--per-bag', type=int, default=20)
    ap.add_argument('--out', default=os.path.join(os.path.dirname(os.path.abspath(__file__)), 'window_scans.npz'))
    a = ap.parse_args()
    openings = world_openings(a.world)
    rows = []
    for spec in a.bags:
        path, index, laser_z = spec.rsplit(':', 2)
        index, laser_z = int(index), float(laser_z)
        truths, scans, kept = [], [], []
        with rosbag.Bag(path) as bag:
            for topic, msg, t in bag.read_messages():
                if topic == '/sim/robots' and len(msg.poses) > index:
                    p = msg.poses[index]
                    q = p.orientation
                    yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
                    stamp = msg.header.stamp.to_sec() if msg.header.stamp else t.to_sec()
                    truths.append((stamp, p.position.x, p.position.y, p.position.z + laser_z, yaw))
                elif topic.endswith('/scan'):
                    scans.append(msg)
        for msg in scans:
            pose = truth_at(truths, msg.header.stamp.to_sec())
            if pose is None:
                continue
            for o in openings:
                tr = truth(pose, o)
                if tr is not None:
                    kept.append((np.asarray(msg.ranges, dtype=np.float32), msg.angle_min, msg.angle_increment,
                                 msg.range_min, msg.range_max, *tr, os.path.basename(path),
                                 any(in_footprint(pose, f) for f in FOOTPRINTS)))
                    break
        chosen = []
        for side in (False, True):                       # outside (approaching), inside (leaving), half each
            some = [k for k in kept if k[-1] == side]
            step = max(1, len(some) // (a.per_bag // 2))
            chosen += some[::step][:a.per_bag // 2]
        rows += chosen
        print(f'{path}: {len(kept)} scans facing an opening, {len(chosen)} kept')
    np.savez_compressed(a.out, ranges=np.stack([r[0] for r in rows]),
                        angle_min=np.array([r[1] for r in rows]), angle_increment=np.array([r[2] for r in rows]),
                        range_min=np.array([r[3] for r in rows]), range_max=np.array([r[4] for r in rows]),
                        lateral=np.array([r[5] for r in rows]), distance=np.array([r[6] for r in rows]),
                        width=np.array([r[7] for r in rows]), source=np.array([r[8] for r in rows]),
                        inside=np.array([r[9] for r in rows]))
    print(f'{a.out}: {len(rows)} scans')


if __name__ == '__main__':
    main()
