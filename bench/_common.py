"""What every benchmark script shares: where the workspace and the results are, the machine's load average
next to the figures, and writing bench/results/<name>.json.

No benchmark sets the nodes' environment (thread counts and the like): each measures the code the way
`roslaunch` runs it (the node packages set single-threaded numerics themselves, at import).

Not a benchmark itself (tools/run_bench.sh runs bench_*.py only). The scripts import it as `_common`:
Python puts the script's own folder, bench/, first on sys.path.
"""
import json
import os
import signal
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SRC = os.path.join(ROOT, "catkin_ws", "src")
# BENCH_RESULTS_DIR: write elsewhere (a trial run, a --quick check) without replacing the reference figures.
RESULTS = os.environ.get("BENCH_RESULTS_DIR") or os.path.join(HERE, "results")


def use_sources(*paths: str) -> None:
    """Puts catkin_ws/src/<path> folders first on sys.path, so a benchmark runs on the source tree
    without a catkin build (e.g. "mbzirc_agents/src")."""
    sys.path[:0] = [os.path.join(SRC, p) for p in paths]


def stop_launch(launch, timeout: float) -> None:
    """Ctrl+C a roslaunch started in its own process group (start_new_session) as a user would; its whole
    group is killed when it has not ended after timeout s (a node ignoring SIGINT must not outlive a bench)."""
    launch.send_signal(signal.SIGINT)
    try:
        launch.wait(timeout)
    except subprocess.TimeoutExpired:
        os.killpg(launch.pid, signal.SIGKILL)
        launch.wait()


def load_average_1min() -> float:
    """The 1-minute load average: on a shared machine, the context a timing figure needs."""
    return round(os.getloadavg()[0], 1)


def load_averages() -> list:
    """The 1, 5 and 15-minute load averages."""
    return [round(x, 2) for x in os.getloadavg()]


def write_result(name: str, result: dict, indent: int = 2, say: bool = True) -> str:
    """Writes `result` as RESULTS/<name>.json (what tools/run_bench.sh merges into latest.json)."""
    os.makedirs(RESULTS, exist_ok=True)
    path = os.path.join(RESULTS, f"{name}.json")
    with open(path, "w", encoding="utf-8") as f:
        json.dump(result, f, indent=indent)
    if say:
        print(f"wrote {os.path.relpath(path, ROOT) if path.startswith(ROOT) else path}")
    return path
