"""Water jet: where the water leaving a nozzle lands and how much of it enters a fire's container.

Model: the jet is straight along the nozzle axis up to JET_RANGE; it makes a spot whose radius grows with the
distance flown (JET_SPREAD_R0 + JET_SPREAD_PER_M * d). When it meets a wall face holding a fire, the share
of the flow entering the hole is the area of the spot inside the hole disc over the spot area. Water that
hits a wall elsewhere, or flies further than JET_RANGE, is lost. `WaterLedger` keeps, per robot, where its
water went (the referee's account, /sim/water).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
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


AIM_MARGIN = 1.0   # m beyond JET_RANGE within which a holder in front of the nozzle counts as the one pumped at


@dataclass
class Pour:
    """Litres of one robot at one holder: pumped while at it (`aimed`), of those the litres that hit a wall
    or fell short, and the litres that entered its container (from whichever aim)."""
    aimed: float = 0.0
    entered: float = 0.0
    on_wall: float = 0.0
    fell_short: float = 0.0


@dataclass
class WaterUse:
    """Where one robot's water went since the start (litres). pumped = into_fires + on_walls + fell_short."""
    pumped: float = 0.0
    into_fires: float = 0.0
    on_walls: float = 0.0
    fell_short: float = 0.0
    pours: dict = field(default_factory=dict)   # holder index (None: no holder in front) -> Pour

    def pour(self, holder: Optional[int]) -> Pour:
        p = self.pours.get(holder)
        if p is None:
            p = self.pours[holder] = Pour()
        return p


class WaterLedger:
    """The referee's account of the water: per robot, litres pumped, entered each fire's container, hit a
    wall (beside the hole, an inactive holder's hole, any other face) or fell short (past JET_RANGE, on the
    ground). Ground truth for /sim/water and tests; no robot reads it.

    The holder pumped at is the nearest fire holder (active or not) whose face the nozzle is in front of and
    the jet points at, within JET_RANGE + AIM_MARGIN: so a miss is charged to the fire the robot was working
    on, and "efficiency of indoor pours" can be told from facade ones.

    .. note:: Only a tick with water leaving a nozzle costs anything (a few numpy operations on the holders).
    """

    def __init__(self, fires: FireSet):
        self.fires = fires
        self.idx = fires.water_idx
        self.pos = fires.pos[self.idx]
        self.normal = fires.normal[self.idx]
        self.offset = np.einsum("ij,ij->i", self.pos, self.normal)   # a point p is in front when n.p > this
        self.robots: dict[int, WaterUse] = {}

    def aimed_holder(self, nozzle: np.ndarray, direction: np.ndarray) -> Optional[int]:
        """Index (in fires) of the holder pumped at, or None."""
        if len(self.idx) == 0:
            return None
        rel = nozzle - self.pos
        dist2 = (rel * rel).sum(axis=1)
        ok = (self.normal @ nozzle > self.offset) & (self.normal @ direction < 0.0) \
            & (dist2 <= (C.JET_RANGE + AIM_MARGIN) ** 2)
        if not ok.any():
            return None
        return int(self.idx[np.where(ok, dist2, np.inf).argmin()])

    def add(self, rid: int, litres: float, into: float, jet: JetResult, nozzle: np.ndarray,
            direction: np.ndarray) -> None:
        """Account `litres` leaving robot rid's nozzle as `jet`, `into` of them credited to jet.fire's
        container (FireSet.add_water; 0 for an inactive holder's hole: that water hit a wall)."""
        use = self.robots.get(rid)
        if use is None:
            use = self.robots[rid] = WaterUse()
        pour = use.pour(self.aimed_holder(nozzle, direction))
        use.pumped += litres
        pour.aimed += litres
        if into > 0.0:
            use.into_fires += into
            use.pour(jet.fire).entered += into
        rest = litres - into
        if jet.hit_wall:
            use.on_walls += rest
            pour.on_wall += rest
        else:
            use.fell_short += rest
            pour.fell_short += rest
