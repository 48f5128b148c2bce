"""Numeric nodes run with one OpenBLAS thread, whoever starts them (issue 22).

Why: the nodes' matrices are small; OpenBLAS's worker threads (one per core by default) then cost more than
they save, and spin between calls: hector_mapping cost 73 CPU-ms per scan with them, 6 without. Each node's
package sets OPENBLAS_NUM_THREADS=1 at import, before numpy loads, unless the user set a number.

The check runs a node script's imports (what `rosrun` and `roslaunch` execute before the node starts) in a
fresh process with no OPENBLAS_NUM_THREADS, makes OpenBLAS work on a matrix product big enough for its
threads, and counts the process's threads in /proc: one. The control (numpy imported alone) shows that
the count would be larger without the package's setting, on a machine with more than one core.
"""
import os
import pathlib
import re
import subprocess
import sys

import pytest

SRC = pathlib.Path(__file__).resolve().parents[1] / "catkin_ws" / "src"
NODE_SCRIPTS = ["hector_mapping/scripts/hector_mapping", "ual_sim/scripts/ual_sim_node",
                "fire_detector/scripts/fire_detector", "circle_detector/scripts/circle_detector",
                "indoor_localization/scripts/indoor_pose", "object_estimation/scripts/object_estimator",
                "mbzirc_agents/scripts/uav_agent", "mbzirc_agents/scripts/ugv_agent",
                "mbzirc_central_unit/scripts/central_unit_node.py", "shared_regions_manager/scripts/region_manager"]
COUNT_THREADS = ("import numpy, os\n"
                 "a = numpy.ones((512, 512))\n"
                 "for _ in range(5): a @ a\n"
                 "print(len(os.listdir('/proc/self/task')))\n")


def threads_after(imports: str) -> int:
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", imports + "\n" + COUNT_THREADS], env=env, capture_output=True,
                         text=True, timeout=60, check=True)
    return int(out.stdout.split()[-1])


def script_imports(script: str) -> str:
    """The script's code before `if __name__ == "__main__":` (its imports)."""
    text = (SRC / script).read_text()
    return re.split(r"""if __name__ == ['"]__main__['"]:""", text)[0]


@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one core: OpenBLAS starts no worker anyway")
def test_control_numpy_alone_starts_blas_workers():
    assert threads_after("") > 1


@pytest.mark.parametrize("script", NODE_SCRIPTS)
def test_node_script_runs_one_blas_thread(script):
    assert threads_after(script_imports(script)) == 1


def test_user_setting_wins():
    """A user who asks for threads gets them (the packages only set a default)."""
    if len(os.sched_getaffinity(0)) < 2:
        pytest.skip("one core")
    env_code = "import os; os.environ['OPENBLAS_NUM_THREADS'] = '2'\n"
    assert threads_after(env_code + script_imports(NODE_SCRIPTS[0])) == 2
