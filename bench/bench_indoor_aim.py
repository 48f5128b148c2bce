#!/usr/bin/env python3
"""Benchmark: how well a UAV's thermal aim keeps its jet in an indoor fire's hole (issue 17), on ual_sim's
own renderer and jet under its `realistic` profile, without ROS.

Side by side in one run:
  bearings - a UAV facing an indoor fire at 1.0, 1.2, 1.5 (the watering distance) and 2.0 m, its heading
             off by a few degrees: the fire centre's true bearing from the camera, the fire detector's (its
             hot contours' centroid), the centroid of the raw frame's warm core (the agents' warm spot before
             725d3d0) and thermal_contrast.warm_spot (the hole the ring of flames encloses, when it fills the
             view);
  pours    - the UAV pours its 2 L from 1.5 m, aimed at the fire's centre at the start, holding its GNSS
             set-point while the GNSS bias wanders (the height held on the truth, as the altimeter hold does):
             litres into the fire with the heading frozen, and turned every 0.5 s onto the warm core's
             centroid or onto warm_spot when either reads 0.03 rad (~aim_bearing_tolerance) or more off.
The fire never goes out (its need is set high) so that the whole tank measures the aim; inactive holders are
lit. Writes bench/results/indoor_aim.json.
Usage: bench_indoor_aim.py [--seeds 12]
"""
from __future__ import annotations

import argparse
import math

import numpy as np

from _common import load_averages, use_sources, write_result

use_sources("ual_sim/src", "fire_detector/src", "mbzirc_agents/src")

from fire_detector import constants as FC  # noqa: E402
from fire_detector.thermal import find_hot_spot  # noqa: E402
from mbzirc_agents.tasks.thermal_contrast import lock_masks, pixel_bearing, warm_spot  # noqa: E402
from ual_sim import constants as SC  # noqa: E402
from ual_sim.sim import Simulation  # noqa: E402
from ual_sim.thermal import FORWARD  # noqa: E402
from ual_sim.uncertainty import profile  # noqa: E402
from ual_sim.world import load_world  # noqa: E402

FIRE = (17.9, 16.5, 6.5)      # the default world's in1_e (floor 1, east room)
FOV = 33.0                    # deg: the agents' ~forward_camera_fov
MIN_RISE = 4.0                # deg C: thermal_contrast.LOCK_MIN_RISE x the default ~out_contrast
TOLERANCE = 0.03              # rad: the agents' default ~aim_bearing_tolerance
PERIOD = 0.5                  # s: extinguish_indoor_fire's watering loop


def core_centroid(frame):
    masks = lock_masks(frame, MIN_RISE)
    if masks is None:
        return None
    rows, cols = np.nonzero(masks[0])
    return float(cols.mean()), float(rows.mean()), True


def new_centre(frame):
    return warm_spot(frame, MIN_RISE)


def trial(world, seed):
    sim = Simulation(world, seed=seed, uncertainty=profile(world.uncertainty, "realistic"))
    i = int(np.argmin(np.linalg.norm(sim.fires.pos - np.array(FIRE), axis=1)))
    sim.fires.fires[i].active = True
    sim.fires.fires[i].litres_needed = 100.0
    return sim, i


def place(sim, i, dist, yaw_error):
    c, n = sim.fires.pos[i], sim.fires.normal[i]
    r = sim.robots[2]
    r.state, r.pos = SC.FLYING_AUTO, c + n * dist
    r.yaw = math.atan2(-n[1], -n[0]) + yaw_error
    r.goal, r.goal_yaw, r.mode = r.pos.copy(), r.yaw, "idle"
    sim._cache.clear()
    return r


def bearings(world):
    sim, i = trial(world, 201)
    rows = []
    for dist in (1.0, 1.2, 1.5, 2.0):
        for err in (-8.0, -5.0, -3.0, 3.0, 5.0, 8.0):
            r = place(sim, i, dist, math.radians(err))
            frame = sim.thermal_frame(r, FORWARD)
            cam = r.sensor_base() + SC.THERMAL_OFFSET_FORWARD[0] * np.array([math.cos(r.yaw), math.sin(r.yaw), 0])
            rel = sim.fires.pos[i] - cam
            true = math.degrees(math.remainder(math.atan2(rel[1], rel[0]) - r.yaw, 2 * math.pi))
            spot = find_hot_spot(frame, FC.DEFAULT_THERMAL_THRESHOLD, FC.DEFAULT_MIN_CONTRAST,
                                 FC.DEFAULT_SATURATION_TEMPERATURE, FC.DEFAULT_BAND_MAX_FILL)
            read = {"detector": None if spot is None else math.degrees(pixel_bearing(spot.u, FOV))}
            for name, fn in (("core_centroid", core_centroid), ("warm_spot", new_centre)):
                s = fn(frame)
                read[name] = None if s is None else math.degrees(pixel_bearing(s[0], FOV))
            rows.append({"distance": dist, "true": round(true, 1),
                         **{k: None if v is None else round(v, 1) for k, v in read.items()}})
    return rows


def pour(world, seed, aim):
    sim, i = trial(world, seed)
    r = place(sim, i, 1.5, 0.0)
    z = sim.fires.pos[i][2]
    r.water, r.pump_on = 2.0, True
    dt, t, last = 0.05, 0.0, 0.0
    while r.water > 0.0 and t < 30.0:
        sim.step(dt)
        r.goal[2] = z
        t += dt
        if aim is not None and t - last >= PERIOD - 1e-9:
            last = t
            s = aim(sim.thermal_frame(r, FORWARD))
            if s is not None and abs(pixel_bearing(s[0], FOV)) >= TOLERANCE:
                rep = sim.reported_pose(r)
                r.go_to(rep[0], rep[1], rep[2], r.yaw + pixel_bearing(s[0], FOV))
    return sim.fires.fires[i].litres


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=12)
    args = ap.parse_args()
    world = load_world()
    rows = bearings(world)
    print("bearing of the fire's centre (deg): distance, true, detector, core centroid, warm_spot")
    for row in rows:
        print(f"  {row['distance']:.1f} m  {row['true']:+6.1f}  {row['detector']}  {row['core_centroid']}  "
              f"{row['warm_spot']}")
    seeds = list(range(201, 201 + args.seeds))
    pours = {}
    for name, aim in (("frozen", None), ("core_centroid", core_centroid), ("warm_spot", new_centre)):
        got = [pour(world, s, aim) for s in seeds]
        pours[name] = {"mean": round(float(np.mean(got)), 2), "min": round(float(np.min(got)), 2),
                       "litres": [round(g, 2) for g in got]}
        print(f"pour 2 L from 1.5 m, {name:14s}: into the fire mean {pours[name]['mean']:.2f} L, "
              f"min {pours[name]['min']:.2f} L")
    write_result("indoor_aim", {"seeds": seeds, "bearings": rows, "pours": pours, "load": load_averages()})


if __name__ == "__main__":
    main()
