#!/usr/bin/env python3
"""Benchmark of hector_mapping (Python + NumPy): throughput on one core and accuracy on indoor flights.

Throughput: scans per CPU second (one core) of the whole per-scan pipeline (range filtering, coarse-to-fine matching,
map update when the thresholds say so) for ual_sim's 720-beam laser, a 2048 x 2048 map at 0.05 m with
2 levels (the thesis's settings), pinned to one core, numpy as the node runs it (one OpenBLAS thread).
Four cases: matching only (no map update), every scan updating the map (worst case), and the thesis's
thresholds on the slow and on the fast-turning flight. The node as launched: bench_hector_node.py.

Accuracy: simulated flights on the tower's first floor of ual_sim's world (laser at 15 Hz, 1 cm range
noise, no odometry): a slow one (0.3 m/s, turning on the spot at 0.5 rad/s) and a fast one (1 m/s while
turning at the 1 rad/s yaw limit). Several runs each (different first scan and noise seed); reported:
ATE (RMS after rigid alignment), the stricter start-aligned error, and the map's occupied cells against
the world's walls; the worst run is what counts. The same fast runs with the original's matching
(start from the last pose, fixed 4/6 iterations, no rotation search) show how often that loses track.

Writes bench/results/hector.json.
"""
from __future__ import annotations

import os
import time

from _common import load_average_1min, use_sources, write_result

use_sources("hector_mapping/src", "hector_mapping/test")

# hector_mapping before numpy: the package sets numpy's threads up as in the node
import indoor  # noqa: E402  (hector_mapping's test fixtures)
import sim2d  # noqa: E402
from hector_mapping.geometry import transform_points  # noqa: E402
from hector_mapping.scan import ScanFilter, scan_to_points  # noqa: E402
from hector_mapping.slam import HectorSlam, SlamParams  # noqa: E402

import numpy as np  # noqa: E402,I100

RATE = 15.0
NOISE = 0.01
THESIS = dict(map_resolution=0.05, map_size=2048, map_start_x=0.5, map_start_y=0.5, map_multi_res_levels=2,
              update_factor_free=0.4, update_factor_occupied=0.9, map_update_distance_thresh=0.4,
              map_update_angle_thresh=0.06)
ORIGINAL_MATCHING = dict(use_motion_prediction=False, rotation_search=False, iterate_to_convergence=False)
SLOW_STARTS = (0, 4, 9)
FAST_STARTS = (0, 1, 2, 3, 4, 5, 6, 7)
LOST = 0.5          # m: an ATE above this is a lost track


def pin_one_core() -> None:
    """Run on one core so that the figure is a single-core one."""
    try:
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    except (AttributeError, OSError):
        pass


def run(scans: np.ndarray, flight: sim2d.Flight, start: int, params: SlamParams,
        timed: bool = False) -> tuple[np.ndarray, float, HectorSlam]:
    """Process scans[start:] through a fresh SLAM; the estimates, scans per CPU second and the SLAM.

    Throughput is measured in CPU time of this (single-threaded, one-core) process, so that other jobs
    on the shared machine do not distort it; :func:`throughput` also reports the wall-clock figure.
    """
    slam = HectorSlam(params)
    flt = ScanFilter()
    est = np.empty((len(scans) - start, 3))
    t0 = time.process_time()
    for i, k in enumerate(range(start, len(scans))):
        pts = scan_to_points(scans[k], sim2d.ANGLE_MIN, sim2d.ANGLE_INCREMENT, sim2d.RANGE_MIN,
                             sim2d.RANGE_MAX, flt)
        est[i] = slam.process(pts, np.zeros(2), float(flight.t[k])).pose
    dt = time.process_time() - t0
    return est, (len(scans) - start) / dt if timed else 0.0, slam


def map_check(slam: HectorSlam, start_pose: np.ndarray, seen: np.ndarray, world: indoor.IndoorWorld) -> dict:
    """Occupied cells of the finest level against the world's walls (arena frame)."""
    lv = slam.levels[0]
    occ = np.argwhere(lv.occupancy_grid_data() == 100)[:, ::-1].astype(float)
    occ_arena = transform_points(start_pose, lv.map_to_world(occ))
    out = indoor.map_wall_check(occ_arena, seen, world.segments, lv.resolution)
    out["occupied_cells"] = int(len(occ))
    return out


def seen_walls(clean: np.ndarray, flight: sim2d.Flight) -> np.ndarray:
    """Noise-free beam endpoints (arena) along the flight, thinned: the wall surfaces the laser saw."""
    pts = []
    for k in range(0, len(clean), 3):
        c = scan_to_points(clean[k], sim2d.ANGLE_MIN, sim2d.ANGLE_INCREMENT, 0.0, 1e9, ScanFilter(0.0, 1e9))
        pts.append(transform_points(flight.poses[k], c))
    p = np.concatenate(pts)
    _, first = np.unique(np.floor(p / 0.025).astype(np.int64), axis=0, return_index=True)
    return p[first]


def throughput(world: indoor.IndoorWorld, slow: sim2d.Flight, slow_scans: np.ndarray,
               fast: sim2d.Flight, fast_scans: np.ndarray) -> dict:
    """Scans per second, one core, for the four cases."""
    n = 450
    sub_slow = sim2d.Flight(slow.t[:n], slow.poses[:n])
    sub_fast = sim2d.Flight(fast.t[:n], fast.poses[:n])
    out = {}
    cases = {
        "match_only": (dict(THESIS, map_update_distance_thresh=1e9, map_update_angle_thresh=1e9), sub_slow,
                       slow_scans[:n]),
        "update_every_scan": (dict(THESIS, map_update_distance_thresh=-1.0, map_update_angle_thresh=-1.0),
                              sub_fast, fast_scans[:n]),
        "thesis_thresholds_slow_flight": (THESIS, sub_slow, slow_scans[:n]),
        "thesis_thresholds_fast_flight": (THESIS, sub_fast, fast_scans[:n]),
    }
    for name, (params, flight, scans) in cases.items():
        w0 = time.perf_counter()
        _, rate, _ = run(scans, flight, 0, SlamParams(**params), timed=True)
        wall = len(scans) / (time.perf_counter() - w0)
        out[name] = round(rate, 1)
        out[name + "_wall_clock"] = round(wall, 1)
        print(f"  {name:32s} {rate:7.1f} scans per CPU second ({wall:.1f} per wall second, shared machine)")
    return out


def accuracy(world: indoor.IndoorWorld, name: str, flight: sim2d.Flight, starts, seeds_base: int,
             original_too: bool) -> dict:
    """Several runs of one flight; per run ATE, start-aligned error, map check."""
    clean = indoor.scans_along(world, flight, 0.0, 0)
    seen = seen_walls(clean, flight)
    runs, orig_runs = [], []
    for i, start in enumerate(starts):
        scans = indoor.scans_along(world, flight, NOISE, seeds_base + i)
        est, _, slam = run(scans, flight, start, SlamParams(**THESIS))
        r = {"first_scan": start, "seed": seeds_base + i, **indoor.ate(est, flight.poses[start:]),
             "map": map_check(slam, flight.poses[start], seen, world)}
        runs.append(r)
        print(f"  {name} run {i} (first scan {start:2d}): ATE rms {r['ate_rms']:.4f} max {r['ate_max']:.4f} m, "
              f"start-aligned rms {r['start_aligned_rms']:.4f} max {r['start_aligned_max']:.4f} m, "
              f"map on-wall {r['map']['on_wall']:.3f} coverage {r['map']['coverage']:.3f}")
        if original_too:
            est_o, _, _ = run(scans, flight, start, SlamParams(**THESIS, **ORIGINAL_MATCHING))
            o = indoor.ate(est_o, flight.poses[start:])
            o["first_scan"] = start
            orig_runs.append(o)
            print(f"      original matching: ATE rms {o['ate_rms']:.4f} m"
                  f"{'  LOST' if o['ate_rms'] > LOST else ''}")
    worst = {k: max(r[k] for r in runs) for k in ("ate_rms", "ate_max", "start_aligned_rms", "start_aligned_max")}
    worst["map_on_wall"] = min(r["map"]["on_wall"] for r in runs)
    worst["map_coverage"] = min(r["map"]["coverage"] for r in runs)
    worst["map_max_distance"] = max(r["map"]["max_distance"] for r in runs)
    out = {"scans": len(flight.poses), "duration_s": round(float(flight.t[-1]), 1), "runs": runs, "worst": worst}
    if original_too:
        out["original_matching"] = {"runs": orig_runs, "lost": sum(o["ate_rms"] > LOST for o in orig_runs),
                                    "of": len(orig_runs)}
    return out


def main() -> None:
    pin_one_core()
    world = indoor.world_source()
    print(f"world: {world.source}")
    slow = indoor.slow_flight(world, RATE)
    fast = indoor.fast_turning_flight(world, RATE)
    t0 = time.time()
    slow_scans = indoor.scans_along(world, slow, NOISE, 100)
    fast_scans = indoor.scans_along(world, fast, NOISE, 200)
    print("throughput (720 beams, 2048 x 2048 at 0.05 m, 2 levels, one core):")
    tp = throughput(world, slow, slow_scans, fast, fast_scans)
    print("accuracy (laser 15 Hz, 1 cm noise, no odometry):")
    acc_slow = accuracy(world, "slow", slow, SLOW_STARTS, 100, original_too=False)
    acc_fast = accuracy(world, "fast", fast, FAST_STARTS, 200, original_too=True)
    worst_ate = max(acc_slow["worst"]["ate_rms"], acc_fast["worst"]["ate_rms"])
    result = {
        "world": world.source,
        "settings": {"beams": sim2d.N_BEAMS, "map_size": 2048, "resolution": 0.05, "levels": 2,
                     "laser_rate_hz": RATE, "range_noise_m": NOISE, "one_core": True},
        "throughput_scans_per_s": tp,
        "throughput_target_scans_per_s": 100,
        "slow_flight": acc_slow,
        "fast_turning_flight": acc_fast,
        "worst_ate_rms_m": worst_ate,
        "ate_target_m": 0.05,
        "wall_time_s": round(time.time() - t0, 1),
        "load_average_1min_at_end": load_average_1min(),
    }
    print(f"worst ATE rms over all runs: {worst_ate:.4f} m (target < 0.05); worst start-aligned rms: "
          f"{max(acc_slow['worst']['start_aligned_rms'], acc_fast['worst']['start_aligned_rms']):.4f} m")
    print(f"original matching lost track in {acc_fast['original_matching']['lost']} of "
          f"{acc_fast['original_matching']['of']} fast runs; ours in "
          f"{sum(r['ate_rms'] > LOST for r in acc_fast['runs'])}")
    write_result("hector", result, indent=1)


if __name__ == "__main__":
    main()
