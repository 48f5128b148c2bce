"""Fires of a trial: which holders the seed activates, water received, blankets, temperatures and score.

Facade and indoor fires are put out with water (litres in the container / litres needed, capped at 1);
ground fires with a blanket (1 when it covers the plate). The score is the sum over active fires.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import constants as C
from .world import Holder, World

FACADE, GROUND, INDOOR = 0, 1, 2
_KIND = {"facade": FACADE, "ground": GROUND, "indoor": INDOOR}


@dataclass
class Fire:
    """One fire holder and its state; inactive holders are kept (they are cold decoys for the sensors)."""
    holder: Holder
    kind: int
    active: bool
    litres: float = 0.0
    covered: bool = False
    extinguish_time: float = -1.0
    litres_needed: float = C.LITRES_PER_FIRE   # per fire: the trial's uncertainty may scale it (uncertainty.py)

    @property
    def progress(self) -> float:
        """Score of this fire in [0, 1]."""
        if not self.active:
            return 0.0
        if self.kind == GROUND:
            return 1.0 if self.covered else 0.0
        return min(1.0, self.litres / self.litres_needed)

    @property
    def extinguished(self) -> bool:
        return self.active and self.progress >= 1.0

    @property
    def heat_fraction(self) -> float:
        """How hot the fire still is: 1 when untouched, cooling linearly as water arrives, 0 when out."""
        return 0.0 if not self.active else 1.0 - self.progress


class FireSet:
    """All holders of a world with the seed's choice of active ones, plus vectorised geometry for sensors."""

    def __init__(self, world: World, seed: int = 0):
        rng = np.random.default_rng(seed)
        self.fires: list[Fire] = []
        per_floor_f = int(world.active.get("facade_per_floor", 1))
        per_floor_i = int(world.active.get("indoor_per_floor", 1))
        n_ground = int(world.active.get("ground", 2))
        for holders, per in ((world.facade_holders, per_floor_f), (world.indoor_holders, per_floor_i)):
            floors = sorted({h.floor for h in holders})
            chosen = set()
            for fl in floors:
                ids = [i for i, h in enumerate(holders) if h.floor == fl]
                chosen.update(rng.choice(ids, size=min(per, len(ids)), replace=False).tolist())
            for i, h in enumerate(holders):
                self.fires.append(Fire(h, _KIND[h.kind], i in chosen))
        g_ids = list(range(len(world.ground_holders)))
        g_chosen = set(rng.choice(g_ids, size=min(n_ground, len(g_ids)), replace=False).tolist()) if g_ids else set()
        for i, h in enumerate(world.ground_holders):
            self.fires.append(Fire(h, GROUND, i in g_chosen))
        if world.active_ids is not None:
            for f in self.fires:
                f.active = f.holder.id in world.active_ids
        self.pos = np.array([f.holder.position for f in self.fires], dtype=float).reshape(-1, 3)
        self.normal = np.array([f.holder.normal for f in self.fires], dtype=float).reshape(-1, 3)
        self.kind = np.array([f.kind for f in self.fires], dtype=int)
        self.water_idx = np.nonzero(self.kind != GROUND)[0]
        self.ground_idx = np.nonzero(self.kind == GROUND)[0]
        # in-plane axes of the wall fires: u horizontal (normal x z), v = z
        u = np.cross(self.normal, np.array([0.0, 0.0, 1.0]))
        n = np.linalg.norm(u, axis=1, keepdims=True)
        self.u = np.where(n > 1e-9, u / np.where(n > 1e-9, n, 1.0), np.array([1.0, 0.0, 0.0]))

    version = 0   # bumped on every change that a sensor could see (sensor caches key on it)

    def by_id(self, fire_id: str) -> Optional[Fire]:
        """The fire of a holder id, or None."""
        return next((f for f in self.fires if f.holder.id == fire_id), None)

    def active(self) -> list[Fire]:
        return [f for f in self.fires if f.active]

    def add_water(self, i: int, litres: float, now: float) -> float:
        """Credit litres to fire i's container; stamps the extinguish time when it reaches the need. Returns
        the litres credited (0 for an inactive holder or a ground fire)."""
        f = self.fires[i]
        if not f.active or f.kind == GROUND or litres <= 0.0:
            return 0.0
        was = f.extinguished
        f.litres += litres
        self.version += 1
        if f.extinguished and not was:
            f.extinguish_time = now
        return litres

    def drop_blanket(self, x: float, y: float, height: float, now: float) -> Optional[int]:
        """A blanket released at (x, y) from `height` m: returns the index of the fire it covers, if any."""
        if height > C.BLANKET_MAX_HEIGHT or len(self.ground_idx) == 0:
            return None
        d = np.hypot(self.pos[self.ground_idx, 0] - x, self.pos[self.ground_idx, 1] - y)
        k = int(d.argmin())
        if d[k] > C.BLANKET_MAX_OFFSET:
            return None
        i = int(self.ground_idx[k])
        f = self.fires[i]
        self.version += 1
        if not f.covered:
            f.covered = True
            if f.active:
                f.extinguish_time = now
        return i

    def heat(self) -> np.ndarray:
        """(F,) heat fraction of each holder (0 for inactive or extinguished)."""
        return np.array([f.heat_fraction for f in self.fires])

    def score(self) -> float:
        return float(sum(f.progress for f in self.fires))

    def max_score(self) -> int:
        return sum(1 for f in self.fires if f.active)
