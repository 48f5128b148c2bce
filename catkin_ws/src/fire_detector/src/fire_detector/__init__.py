"""Thermal fire detection for the MBZIRC 2020 Challenge 3 UAVs (pure logic + a thin ROS node).

Importing it first (the node's script does) makes NumPy's OpenBLAS single-threaded.
"""

import os as _os

# One OpenBLAS thread unless the user set another number: see the README, "single-threaded numerics".
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
