#!/usr/bin/env python3
"""Setup idempotency: how long `setup/setup.sh` takes when nothing changed (the cost every `make` pays).

The first run (apt, venv, catkin_make) takes minutes; later ones must take seconds. This measures the
no-op run a few times and reports the median, next to one build of the workspace for the ratio.
"""
import pathlib
import statistics
import subprocess
import time

from _common import write_result

ROOT = pathlib.Path(__file__).resolve().parents[1]


def timed(cmd):
    t0 = time.monotonic()
    subprocess.run(cmd, cwd=ROOT, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.monotonic() - t0


def main():
    timed(["bash", "setup/setup.sh"])  # make sure we start from a set-up tree
    noop = [timed(["bash", "setup/setup.sh"]) for _ in range(3)]
    stamp = ROOT / ".setup-stamps" / "catkin"
    stamp.write_text("force-rebuild\n")  # the catkin_make step alone, as after an edit of a .msg
    rebuild = timed(["bash", "setup/setup.sh"])
    result = {"noop_setup_s": round(statistics.median(noop), 2), "catkin_rebuild_s": round(rebuild, 2),
              "ratio_rebuild_over_noop": round(rebuild / statistics.median(noop), 1)}
    print(f"setup with nothing changed: {result['noop_setup_s']} s (median of 3); "
          f"catkin rebuild: {result['catkin_rebuild_s']} s")
    write_result("setup", result)


if __name__ == "__main__":
    main()
