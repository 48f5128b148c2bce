"""hector_mapping: 2D laser SLAM (after Kohlbrecher et al., SSRR 2011) in Python + NumPy.

The pure core (``grid``, ``matcher``, ``slam``, ``scan``) has no ROS dependency; ``node`` is the thin ROS
adapter used by ``scripts/hector_mapping``.
"""
