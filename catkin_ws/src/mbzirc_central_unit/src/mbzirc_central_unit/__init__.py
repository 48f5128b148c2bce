"""The central unit: the C3 strategy that gives the agents their tasks.

Importing it first (the node's script does) makes NumPy's OpenBLAS single-threaded.
"""

import os as _os

# One OpenBLAS thread unless the user set another number: fire_detector README, "single-threaded numerics".
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
