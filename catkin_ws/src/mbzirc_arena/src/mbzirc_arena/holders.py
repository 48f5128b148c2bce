"""A facade fire estimate and the public holder it belongs to (the agents and the central unit alike).

Why: holder places are known before the trial, while estimates carry the GNSS error of the poses that placed
them (about a metre). A standoff computed from an estimate near a corner put a UAV inside the extension (two
UAVs crashed into its wall beside holder A_4), and the central unit's viewpoint for such an estimate stood
inside the extension's footprint, so that every transit to it was refused and the fire was never watered
(realistic seed 111: A_4 estimated 0.6 m off, nearer the tower's east face, which the extension hides below
4.5 m)."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from .c3 import FACADE_HOLDERS

HOLDER_SNAP = 1.5   # m: a facade fire estimate this close to a known holder is that holder's fire


def nearest_holder(fire: Sequence[float], holders: Sequence = FACADE_HOLDERS) -> tuple:
    """(the public facade holder nearest a point, its distance); (the point, inf) when there is none."""
    fire = np.asarray(fire, dtype=float)
    known = np.asarray(holders, dtype=float).reshape(-1, 3)
    if len(known) == 0:
        return fire, math.inf
    d = np.linalg.norm(known - fire, axis=1)
    i = int(np.argmin(d))
    return known[i], float(d[i])


def known_holder(fire: Sequence[float], holders: Sequence = FACADE_HOLDERS) -> np.ndarray:
    """The public facade holder nearest a fire estimate when within HOLDER_SNAP, else the estimate."""
    holder, d = nearest_holder(fire, holders)
    return holder if d <= HOLDER_SNAP else np.asarray(fire, dtype=float)


__all__ = ['HOLDER_SNAP', 'known_holder', 'nearest_holder']
