"""RGB-D circle (hole) detection and the choice of the hole to shoot, for the C3 water UAVs.

Importing it first (the node's script does) makes NumPy's OpenBLAS single-threaded.
"""

import os as _os

# One OpenBLAS thread unless the user set another number: see the README, "single-threaded numerics".
_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
