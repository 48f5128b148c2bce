"""Water jet: where the water leaving a nozzle lands and how much of it enters a fire's container.

Model: the jet is straight along the nozzle axis up to JET_RANGE; it makes a spot whose radius grows with the
distance flown (JET_SPREAD_R0 + JET_SPREAD_PER_M * d). When it meets a wall face holding a fire, the share
of the flow entering the hole is the area of the spot inside the hole disc over the spot area. Water that
hits a wall elsewhere, or flies further than JET_RANGE, is lost.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import constants as C
from .fires import FireSet
from .world import GROUND as HIT_GROUND, World


def disc_overlap(d: float, r1: float, r2: float) -> float:
    """Area of the intersection of two discs of radii r1, r2 whose centres are d apart."""
    if d >= r1 + r2:
        return 0.0
    if d <= abs(r1 - r2):
        return math.pi * min(r1, r2) ** 2
    a1 = r1 * r1 * math.acos(max(-1.0, min(1.0, (d * d + r1 * r1 - r2 * r2) / (2 * d * r1))))
    a2 = r2 * r2 * math.acos(max(-1.0, min(1.0, (d * d + r2 * r2 - r1 * r1) / (2 * d * r2))))
    k = 0.5 * math.sqrt(max(0.0, (-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2)))
    return a1 + a2 - k


@dataclass
class JetResult:
    """Where the jet ends (for markers) and which fire got how large a share of the flow."""
    end: np.ndarray
    hit_wall: bool
    fire: Optional[int] = None
    share: float = 0.0


def shoot(world: World, fires: FireSet, nozzle: np.ndarray, direction: np.ndarray,
          spot_factor: float = 1.0, drop_per_m2: float = 0.0) -> JetResult:
    """Trace the jet from the nozzle and find the fire container it feeds, if any.

    spot_factor scales the spot's growth per metre and drop_per_m2 lowers where it lands by that times the
    distance squared (the trial's unknowns, uncertainty.py; 1 and 0 = the nominal jet)."""
    t, idx = world.raycast(nozzle, direction[None, :], C.JET_RANGE,
                           boxes=world.boxes_near(nozzle, C.JET_RANGE + 0.5), ground=True)
    t0, i0 = float(t[0]), int(idx[0])
    if not math.isfinite(t0):
        return JetResult(nozzle + direction * C.JET_RANGE, False)
    end = nozzle + direction * t0
    if i0 == HIT_GROUND:
        return JetResult(end, False)
    if drop_per_m2:
        end = end - np.array([0.0, 0.0, drop_per_m2 * t0 * t0])
    spot = C.JET_SPREAD_R0 + C.JET_SPREAD_PER_M * spot_factor * t0
    best, share = None, 0.0
    for i in fires.water_idx:
        c, n = fires.pos[i], fires.normal[i]
        rel = end - c
        if abs(rel @ n) > 0.25 or direction @ n >= 0.0:
            continue
        radial = float(np.linalg.norm(rel - (rel @ n) * n))
        s = disc_overlap(radial, spot, C.HOLE_RADIUS) / (math.pi * spot * spot)
        if s > share:
            best, share = int(i), s
    return JetResult(end, True, best, share)
