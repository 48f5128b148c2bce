"""The UAVs' downward altimeter: a single-beam laser rangefinder under the body, measuring the height of
base_link above the surface below (ground, a roof, a floor slab, a window sill) from the TRUE pose.

Why: a real UAV carries one (PX4 / ArduPilot fuse it for the height near the ground) and it is the only
height a robot can trust near the ground when its GNSS height wanders by decimetres (the ual_sim README,
"Uncertainty"). The sensor's numbers are in constants.py (ALTIMETER_*), their sources in the README
("Altimeter"). `ideal` is noise-free; every other profile adds the datasheet's noise and rare dropouts,
drawn from a generator of its own (a seed's GNSS error is the same whether or not anyone listens).

Readings follow REP 117 (sensor_msgs/Range): -inf below the minimum range (e.g. landed), +inf beyond the
maximum (no return), NaN for an invalid reading.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from . import constants as C


def altimeter_reading(height: float, rng: Optional[np.random.Generator] = None) -> float:
    """What the altimeter reports for a true height (m) of base_link above the surface below.

    rng None: noise-free (`ideal`). Else: NaN with probability ALTIMETER_DROPOUT_RATE, otherwise Gaussian
    noise of ALTIMETER_NOISE_NEAR below ALTIMETER_NEAR_LIMIT and ALTIMETER_NOISE_FAR above it.
    """
    h = float(height)
    if not math.isfinite(h):
        return math.nan
    if rng is not None:
        if rng.random() < C.ALTIMETER_DROPOUT_RATE:
            return math.nan
        std = C.ALTIMETER_NOISE_NEAR if h < C.ALTIMETER_NEAR_LIMIT else C.ALTIMETER_NOISE_FAR
        h += std * float(rng.standard_normal())
    if h < C.ALTIMETER_RANGE_MIN:
        return -math.inf
    if h > C.ALTIMETER_RANGE_MAX:
        return math.inf
    return h


__all__ = ["altimeter_reading"]
