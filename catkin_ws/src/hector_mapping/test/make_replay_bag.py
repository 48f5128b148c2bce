#!/usr/bin/env python3
"""Regenerates test/data/floor1_fast.bag and floor1_fast_walls.json (the rostest's recording).

The flight: ual_sim's default world, tower first floor, the UAV looping through its three rooms at 1 m/s
while turning at its 1 rad/s yaw limit, laser at 15 Hz (720 beams, 1 cm range noise), no odometry.
Topics (as ual_sim with ~tf_odom:=true would give them, for UAV 1):
  /mbzirc2020_1/scan                 sensor_msgs/LaserScan, frame mbzirc2020_1/laser_link
  /tf_static                         mbzirc2020_1/base_link -> mbzirc2020_1/laser_link (z 0.1 m), 1 Hz
  /tf                                mbzirc2020_1/odom -> mbzirc2020_1/base_link (the true pose)
  /mbzirc2020_1/ground_truth/pose    geometry_msgs/PoseStamped in frame arena (for the test only)
The JSON holds wall-surface points (arena frame) hit by noise-free beams along the flight, for the map
check, and the true start pose.

Usage: make_replay_bag.py [out_dir]   (default: the test/data folder next to this script)
"""
from __future__ import annotations

import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src"))

import rosbag  # noqa: E402
import rospy  # noqa: E402
from geometry_msgs.msg import PoseStamped, TransformStamped  # noqa: E402
from sensor_msgs.msg import LaserScan  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402

import indoor  # noqa: E402  (test fixtures in this folder)
import sim2d  # noqa: E402
from hector_mapping.geometry import quaternion_from_yaw  # noqa: E402

NS = "mbzirc2020_1"
T0 = 1000.0
NOISE = 0.01
SEED = 7


def tf(parent: str, child: str, x: float, y: float, z: float, yaw: float, t: rospy.Time) -> TransformStamped:
    m = TransformStamped()
    m.header.stamp = t
    m.header.frame_id = parent
    m.child_frame_id = child
    m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = x, y, z
    r = m.transform.rotation
    r.x, r.y, r.z, r.w = quaternion_from_yaw(yaw)
    return m


def main() -> None:
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")
    os.makedirs(out, exist_ok=True)
    world = indoor.world_source()
    flight = indoor.fast_turning_flight(world)
    scans = indoor.scans_along(world, flight, NOISE, SEED)
    clean = indoor.scans_along(world, flight, 0.0, SEED)
    bag_path = os.path.join(out, "floor1_fast.bag")
    with rosbag.Bag(bag_path, "w", compression=rosbag.Compression.BZ2) as bag:
        t_start = rospy.Time.from_sec(T0)
        mount = TFMessage([tf(f"{NS}/base_link", f"{NS}/laser_link", 0.0, 0.0, indoor.LASER_Z_OFFSET, 0.0,
                              t_start)])
        for k, (t, pose) in enumerate(zip(flight.t, flight.poses)):
            stamp = rospy.Time.from_sec(T0 + float(t))
            if k % 15 == 0:
                # rosbag play does not latch: repeat the static mount every second so that a listener
                # that connects late (or misses the first message) still gets it.
                bag.write("/tf_static", mount, stamp)
            bag.write("/tf", TFMessage([tf(f"{NS}/odom", f"{NS}/base_link", float(pose[0]), float(pose[1]),
                                           indoor.FLIGHT_Z, float(pose[2]), stamp)]), stamp)
            gt = PoseStamped()
            gt.header.stamp = stamp
            gt.header.frame_id = "arena"
            gt.pose.position.x, gt.pose.position.y, gt.pose.position.z = (float(pose[0]), float(pose[1]),
                                                                           indoor.FLIGHT_Z)
            o = gt.pose.orientation
            o.x, o.y, o.z, o.w = quaternion_from_yaw(float(pose[2]))
            bag.write(f"/{NS}/ground_truth/pose", gt, stamp)
            s = LaserScan()
            s.header.stamp = stamp
            s.header.seq = k
            s.header.frame_id = f"{NS}/laser_link"
            s.angle_min = sim2d.ANGLE_MIN
            s.angle_increment = sim2d.ANGLE_INCREMENT
            s.angle_max = sim2d.ANGLE_MIN + sim2d.ANGLE_INCREMENT * (sim2d.N_BEAMS - 1)
            s.scan_time = 1.0 / 15.0
            s.range_min = sim2d.RANGE_MIN
            s.range_max = sim2d.RANGE_MAX
            s.ranges = scans[k].tolist()
            bag.write(f"/{NS}/scan", s, stamp)
    # Wall surface points seen by the laser (noise-free) along the flight.
    pts = []
    ang = sim2d.ANGLE_MIN + sim2d.ANGLE_INCREMENT * np.arange(sim2d.N_BEAMS)
    for k in range(len(flight.poses)):
        x, y, yaw = flight.poses[k]
        r = clean[k]
        ok = np.isfinite(r)
        pts.append(np.stack([x + r[ok] * np.cos(yaw + ang[ok]), y + r[ok] * np.sin(yaw + ang[ok])], 1))
    # one point per 2.5 cm square is plenty for a 5 cm map check
    walls = np.concatenate(pts)
    _, first = np.unique(np.floor(walls / 0.025).astype(np.int64), axis=0, return_index=True)
    walls = np.round(walls[np.sort(first)], 3)
    meta = {"world": world.source, "start_pose": [float(v) for v in flight.poses[0]],
            "final_pose": [float(v) for v in flight.poses[-1]], "n_scans": int(len(flight.poses)),
            "duration": float(flight.t[-1]), "laser_noise": NOISE,
            "wall_points": walls.tolist(), "wall_segments": np.round(world.segments, 4).tolist()}
    with open(os.path.join(out, "floor1_fast_walls.json"), "w") as f:
        json.dump(meta, f, separators=(",", ":"))
    print(f"{bag_path}: {len(flight.poses)} scans, {flight.t[-1]:.1f} s, "
          f"{os.path.getsize(bag_path) / 1e6:.2f} MB; {len(walls)} wall points; world: {world.source}")


if __name__ == "__main__":
    main()
