#!/usr/bin/env python3
"""Benchmark of the smach core and the introspection codec (pure Python, no ROS master).

Figures (all measured in this run):
* StateMachine transitions per second on a two-state CBState loop, and the overhead per transition
  relative to calling the same callbacks in a plain Python loop (ratio);
* mean time of one Concurrence run with 4 instant children (thread start and join cost);
* time to encode a 100-key userdata as introspection local_data, and to decode it with the safe unpickler.
Writes bench/results/smach.json.

``--against REV``: transitions/s of this tree's smach and of the smach of git revision REV, measured side by
side (alternating processes, best of 3 runs each, 8 rounds), and their ratio, per wall second and per CPU
second of the measuring process (on a loaded machine the process waits for a core much of the wall time,
so the CPU ratio is the one to read there; no result file written).
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import smach
from smach_ros.userdata_codec import decode_local_data, encode_local_data

from _common import write_result

N_TRANSITIONS = 20000


def quiet():
    noop = lambda msg: None  # noqa: E731
    smach.set_loggers(noop, noop, noop, noop)


def bench_transitions():
    counter = {"n": 0}

    @smach.cb_interface(outcomes=["next", "end"], input_keys=["n"], output_keys=["n"])
    def ping(ud):
        ud.n = ud.n + 1
        return "end" if ud.n >= N_TRANSITIONS else "next"

    @smach.cb_interface(outcomes=["next"])
    def pong(ud):
        return "next"

    sm = smach.StateMachine(outcomes=["end"])
    sm.userdata.n = 0
    with sm:
        smach.StateMachine.add("PING", smach.CBState(ping), transitions={"next": "PONG", "end": "end"})
        smach.StateMachine.add("PONG", smach.CBState(pong), transitions={"next": "PING"})
    t0, c0 = time.perf_counter(), time.process_time()
    sm.execute()
    t_sm, cpu_sm = time.perf_counter() - t0, time.process_time() - c0
    transitions = 2 * N_TRANSITIONS - 1

    data = {"n": 0}
    t0 = time.perf_counter()
    state = "PING"
    while True:
        if state == "PING":
            data["n"] += 1
            counter["n"] += 1
            if data["n"] >= N_TRANSITIONS:
                break
            state = "PONG"
        else:
            state = "PING"
    t_plain = time.perf_counter() - t0
    return {"transitions": transitions, "transitions_per_s": transitions / t_sm,
            "transitions_per_cpu_s": transitions / max(cpu_sm, 1e-9),
            "us_per_transition": 1e6 * t_sm / transitions,
            "overhead_ratio_vs_plain_loop": t_sm / max(t_plain, 1e-9)}


def bench_concurrence(runs=200):
    cc = smach.Concurrence(outcomes=["done"], default_outcome="done")
    with cc:
        for i in range(4):
            smach.Concurrence.add("C%d" % i, smach.CBState(lambda ud: "done", outcomes=["done"]))
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        cc.execute()
        times.append(time.perf_counter() - t0)
    return {"runs": runs, "children": 4, "mean_ms": 1e3 * statistics.mean(times),
            "p95_ms": 1e3 * sorted(times)[int(0.95 * runs)]}


def bench_codec(reps=300):
    data = {"key%d" % i: ([i, float(i), "v%d" % i] if i % 2 else {"x": i}) for i in range(100)}
    t0 = time.perf_counter()
    for _ in range(reps):
        text = encode_local_data(data)
    t_enc = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    for _ in range(reps):
        decode_local_data(text)
    t_safe = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    for _ in range(reps):
        decode_local_data(text, allow_unsafe=True)
    t_unsafe = (time.perf_counter() - t0) / reps
    return {"keys": 100, "encoded_chars": len(text), "encode_us": 1e6 * t_enc, "safe_decode_us": 1e6 * t_safe,
            "unsafe_decode_us": 1e6 * t_unsafe, "safe_over_unsafe_ratio": t_safe / max(t_unsafe, 1e-12)}


def transitions_per_s_of(smach_src, runs=3):
    """Best of ``runs`` loops, in a fresh process that imports smach from ``smach_src``: (transitions per
    wall second, per CPU second of the process; the latter holds on a loaded machine, where the process
    waits for a core part of the wall time)."""
    env = dict(os.environ, PYTHONPATH=smach_src + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, __file__, "--transitions-only", str(runs)], env=env, check=True,
                         capture_output=True, text=True).stdout
    wall, cpu = out.split()[-2:]
    return float(wall), float(cpu)


def compare_against(rev, rounds=8):
    here = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "catkin_ws", "src", "smach",
                        "src")
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "-C", here, "archive", rev, "."], check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        ours, theirs = [], []
        for _ in range(rounds):
            theirs.append(transitions_per_s_of(tmp))
            ours.append(transitions_per_s_of(here))
    out = {"against": rev, "rounds": rounds, "load_average_1min": os.getloadavg()[0]}
    for i, clock in enumerate(("wall", "cpu")):
        mine, other = [o[i] for o in ours], [t[i] for t in theirs]
        out[clock] = {"ours_best": max(mine), "theirs_best": max(other), "ratio_best": max(mine) / max(other),
                      "ratio_median": statistics.median(mine) / statistics.median(other)}
    print(json.dumps(out, indent=2))


def main():
    if "--transitions-only" in sys.argv:
        quiet()
        runs = int(sys.argv[-1])
        assert os.path.dirname(smach.__file__).startswith(os.environ["PYTHONPATH"].split(os.pathsep)[0])
        loops = [bench_transitions() for _ in range(runs)]
        print(max(o["transitions_per_s"] for o in loops), max(o["transitions_per_cpu_s"] for o in loops))
        return
    if "--against" in sys.argv:
        compare_against(sys.argv[sys.argv.index("--against") + 1])
        return
    quiet()
    out = {"transitions": bench_transitions(), "concurrence": bench_concurrence(), "codec": bench_codec()}
    print(json.dumps(out, indent=2))
    write_result("smach", out)


if __name__ == "__main__":
    main()
