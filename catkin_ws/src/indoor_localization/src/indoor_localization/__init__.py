"""indoor_localization: a robot's pose in the arena frame indoors, from its hector_mapping pose anchored by
its last good GNSS fixes. ``anchor`` is the pure logic (no ROS), ``node`` the ROS adapter.

Importing this package makes NumPy's OpenBLAS single-threaded unless OPENBLAS_NUM_THREADS is already set
(the project's rule for numeric nodes: small matrices, and idle BLAS workers only cost; issue 22).
"""
import os as _os

_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
