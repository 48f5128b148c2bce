"""hector_mapping: 2D laser SLAM (after Kohlbrecher et al., SSRR 2011) in Python + NumPy.

The pure core (``grid``, ``matcher``, ``slam``, ``scan``) has no ROS dependency; ``node`` is the thin ROS
adapter used by ``scripts/hector_mapping``.

Importing this package makes NumPy's OpenBLAS single-threaded unless OPENBLAS_NUM_THREADS is already set,
so it must be imported before numpy (the node's script does). Why: a scan's matrices are small; with its
default threads OpenBLAS hands them to a worker that then spins between scans, and the node as launched
cost 73 CPU-ms per 720-beam scan instead of 6 (bench/bench_hector_node.py).
"""
import os as _os

_os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
