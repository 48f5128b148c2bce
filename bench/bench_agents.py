#!/usr/bin/env python3
"""Benchmark of the mbzirc_agents pure cores (no ROS master): estimator, region manager, planner, framework.

1. Object estimator: three robots see the 8 fires of a trial (3 facade, 2 ground, 3 indoor) for 60 s at
   5 Hz each, with Gaussian position noise (sigma 0.3 / 0.7 / 1.2 m) and 2 % clutter (random false
   detections). Reported per noise level: confirmed tracks (want 8), duplicates, misses, false tracks, mean
   position error of the fused tracks vs the mean error of single detections (the fusion gain), and
   detections/s processed. Baseline in the same run: no cross-robot fusion (one estimator per robot), whose
   track count shows what association buys.
2. Region manager: ask_for_region calls/s with 3 agents holding 3 boxes each, and the share refused.
3. 2D planner (UAV legs and UGV drive around the building): ms per query and path length / straight-line
   distance for random start/goal pairs outside the footprints.
4. Framework: round trip of a trivial task through the action path (submit -> state machine -> result),
   with the fake backend of the unit tests, in ms.

Writes bench/results/agents.json. Usage: bench_agents.py [--quick]
"""
import math
import sys
import time

import numpy as np

from _common import use_sources, write_result

use_sources('mbzirc_arena/src', 'mbzirc_agents/src', 'object_estimation/src', 'shared_regions_manager/src',
            'smach/src', 'mbzirc_agents/test/unit')

from mbzirc_agents import constants as C  # noqa: E402
from mbzirc_arena import c3  # noqa: E402
from object_estimation.core import Detection, ObjectEstimator  # noqa: E402
from mbzirc_arena.buildings import in_footprint  # noqa: E402
from mbzirc_arena.routing import path_length, plan_2d  # noqa: E402
from shared_regions_manager.core import RegionManager  # noqa: E402

QUICK = '--quick' in sys.argv
FIRES = [(12.4, 19.5, 6.5), (24.2, 12.7, 10.5), (11.4, 18.5, 2.75), (-9.0, 20.0, 0.0), (1.0, 14.0, 0.0),
         (17.7, 8.5, 1.5), (17.9, 16.5, 6.5), (17.7, 8.5, 11.5)]


def estimator_run(sigma: float, fuse: bool, rng) -> dict:
    """One trial; fuse=False runs one estimator per robot (no cross-robot association)."""
    ests = {r: ObjectEstimator(min_updates=5, lost_time=10.0) for r in ('1', '2', '3')}
    shared = ObjectEstimator(min_updates=5, lost_time=10.0)
    cov = np.diag([sigma ** 2, sigma ** 2, (sigma / 2) ** 2])
    single_err = []
    n = 0
    t0 = time.perf_counter()
    seconds = 20 if QUICK else 60
    for k in range(seconds * 5):
        t = k / 5.0
        for r in ('1', '2', '3'):
            est = shared if fuse else ests[r]
            for f in FIRES:
                z = np.array(f) + rng.normal(0, [sigma, sigma, sigma / 2])
                single_err.append(float(np.linalg.norm(z - f)))
                est.add(Detection(C.TYPE_FIRE, z, cov, t, r))
                n += 1
            if rng.random() < 0.02 * len(FIRES):
                z = np.array([rng.uniform(-15, 40), rng.uniform(-10, 35), rng.uniform(0, 15)])
                est.add(Detection(C.TYPE_FIRE, z, cov, t, r))
                n += 1
        if k % 5 == 0:
            for e in (ests.values() if not fuse else [shared]):
                e.tick(t)
    dt = time.perf_counter() - t0
    tracks = [tr for e in (ests.values() if not fuse else [shared]) for tr in e.objects()]
    matched = {}
    false = 0
    for tr in tracks:
        d = [np.linalg.norm(tr.position - f) for f in FIRES]
        i = int(np.argmin(d))
        if d[i] <= 2.0:
            matched.setdefault(i, []).append(d[i])
        else:
            false += 1
    errs = [min(v) for v in matched.values()]
    return {'tracks': len(tracks), 'duplicates': sum(len(v) - 1 for v in matched.values()),
            'missed': len(FIRES) - len(matched), 'false_tracks': false,
            'mean_track_error_m': round(float(np.mean(errs)), 3) if errs else None,
            'mean_single_detection_error_m': round(float(np.mean(single_err)), 3),
            'detections_per_s': round(n / dt)}


def bench_estimator() -> dict:
    rng = np.random.default_rng(7)
    out = {}
    for sigma in (0.3, 0.7, 1.2):
        fused = estimator_run(sigma, True, rng)
        alone = estimator_run(sigma, False, rng)
        fused['fusion_gain'] = round(fused['mean_single_detection_error_m'] / fused['mean_track_error_m'], 1) \
            if fused['mean_track_error_m'] else None
        out[f'sigma_{sigma}'] = {'fused': fused, 'per_robot_baseline': alone}
        print(f'estimator sigma {sigma}: fused {fused["tracks"]} tracks (dup {fused["duplicates"]}, '
              f'missed {fused["missed"]}, false {fused["false_tracks"]}), error {fused["mean_track_error_m"]} m '
              f'vs {fused["mean_single_detection_error_m"]} m per detection, {fused["detections_per_s"]} det/s; '
              f'baseline without fusion: {alone["tracks"]} tracks')
    return out


def bench_regions() -> dict:
    rng = np.random.default_rng(3)
    rm = RegionManager()
    for a in ('1', '2', '3'):
        for lab in ('hold', 'go_to', 'take_off'):
            x, y, z = rng.uniform(-15, 40), rng.uniform(-10, 35), rng.uniform(0, 15)
            rm.ask(a, lab, (x, y, z), (x + 2, y + 2, z + 2))
    n = 5000 if QUICK else 50000
    refused = 0
    t0 = time.perf_counter()
    for i in range(n):
        x, y, z = rng.uniform(-15, 40), rng.uniform(-10, 35), rng.uniform(0, 15)
        ok, _ = rm.ask('4', 'probe', (x, y, z), (x + 3, y + 3, z + 3))
        refused += not ok
    dt = time.perf_counter() - t0
    out = {'asks_per_s': round(n / dt), 'refused_share': round(refused / n, 3), 'regions_held': 9}
    print(f'regions: {out["asks_per_s"]} asks/s with 9 boxes held, {out["refused_share"]:.1%} refused')
    return out


def bench_planner() -> dict:
    rng = np.random.default_rng(5)
    times, ratios, fails = [], [], 0
    n = 100 if QUICK else 500
    while len(times) < n:
        s = (rng.uniform(-15, 42), rng.uniform(-12, 36))
        g = (rng.uniform(-15, 42), rng.uniform(-12, 36))
        if in_footprint(s, c3.FOOTPRINTS, 1.6) or in_footprint(g, c3.FOOTPRINTS, 1.6):
            continue
        t0 = time.perf_counter()
        p = plan_2d(s, g, c3.FOOTPRINTS, 1.5)
        times.append(time.perf_counter() - t0)
        if p is None:
            fails += 1
            continue
        d = math.dist(s, g)
        if d > 1.0:
            ratios.append(path_length(p) / d)
    out = {'ms_per_query_median': round(1000 * float(np.median(times)), 3),
           'ms_per_query_p95': round(1000 * float(np.percentile(times, 95)), 3),
           'path_over_straight_mean': round(float(np.mean(ratios)), 3),
           'path_over_straight_max': round(float(np.max(ratios)), 3), 'failures': fails, 'queries': n}
    print(f'planner: {out["ms_per_query_median"]} ms median, path/straight mean {out["path_over_straight_mean"]}'
          f' max {out["path_over_straight_max"]}, {fails} failures of {n}')
    return out


def bench_framework() -> dict:
    from types import SimpleNamespace
    from fake_backend import FakeBackend
    from mbzirc_agents.agent import Agent
    from mbzirc_agents.agent_task import AgentTask

    class Nop(AgentTask):
        def run(self, ud):
            return C.SUCCESS

    be = FakeBackend()
    agent = Agent('b', be)
    agent.add_task('nop', Nop, object(), lambda g, a: {}, SimpleNamespace, None)
    agent.start()
    s = be.servers['nop_action']
    lat = []
    for _ in range(20 if QUICK else 100):
        t0 = time.perf_counter()
        s.send(SimpleNamespace())
        s.wait(5)
        lat.append(time.perf_counter() - t0)
    be.shutdown = True
    agent.shutdown()
    out = {'goal_round_trip_ms_median': round(1000 * float(np.median(lat)), 2),
           'goal_round_trip_ms_max': round(1000 * float(np.max(lat)), 2)}
    print(f'framework: goal round trip {out["goal_round_trip_ms_median"]} ms median '
          f'(state machine polls at {C.CONTROL_RATE_HZ:.0f} Hz)')
    return out


def main() -> None:
    import logging
    import smach
    smach.set_loggers(lambda *a: None, lambda *a: None, lambda *a: None, lambda *a: None)
    logging.disable(logging.INFO)
    res = {'estimator': bench_estimator(), 'regions': bench_regions(), 'planner': bench_planner(),
           'framework': bench_framework(), 'quick': QUICK}
    write_result('agents', res)


if __name__ == '__main__':
    main()
