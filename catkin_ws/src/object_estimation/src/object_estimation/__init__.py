"""Object estimation: fuses the robots' detections into tracks of fires and holes (core), serves them (node).

Importing it first (the node's script does) makes NumPy's OpenBLAS single-threaded: the per-detection 3x3
algebra cost three times the CPU with a worker thread per core.
"""

import os as _os

# One OpenBLAS thread unless the user set another number: fire_detector README, "single-threaded numerics".
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
