"""ual_sim: a kinematic multi-robot simulator of the MBZIRC 2020 Challenge 3 world.

The library is pure Python + NumPy (no ROS import) so that other packages' tests and benchmarks can use
the world model, the ray caster and the sensor models directly; `ual_sim.node` is the thin ROS adapter.
Importing it first (the node's script does) makes NumPy's OpenBLAS single-threaded.
"""

import os as _os

# One OpenBLAS thread unless the user set another number: see the README, "single-threaded numerics".
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
