"""The referee's bookkeeping (pure): what happened in a trial, and the summary.json it ends with.

The mission recorder feeds it ground truth (/sim/fires, /sim/score) and robot tracks; nothing here feeds
back to the strategy.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

from mbzirc_arena.c3 import ARENA

from .indoor_flights import SlamRecord

KIND_NAMES = {0: "facade", 1: "ground", 2: "indoor"}  # ual_sim/FireState kind constants
WATER_KINDS = ("facade", "indoor")                     # fires put out with water
SUMMARY_KEYS = ("seed", "sim_time_s", "wall_time_s", "real_time_factor", "score", "fires_extinguished",
                "fires_total", "crashes", "fires", "robots", "water_efficiency")
FIRE_KEYS = ("id", "kind", "floor", "extinguished_by", "t_extinguished", "litres_received")


@dataclass
class FireRecord:
    """One active fire of the trial as the referee sees it."""
    fire_id: str
    kind: str
    floor: int
    position: tuple[float, float, float]
    progress: float = 0.0
    extinguished: bool = False
    t_extinguished: Optional[float] = None
    extinguished_by: Optional[str] = None
    litres_received: float = 0.0            # in its container (facade, indoor), whoever poured it
    litres_needed: Optional[float] = None


@dataclass
class Pour:
    """One robot's litres at one holder (ual_sim/WaterUse): pumped while at it, entered its container,
    hit a wall, fell short (a robot's pours sum to its litres pumped). fire None: no holder in front."""
    fire: Optional[str]
    kind: Optional[str]
    aimed: float
    entered: float
    on_wall: float
    fell_short: float


def _ratio(num: float, den: float) -> Optional[float]:
    return round(num / den, 3) if den > 1e-9 else None


def _litres(x: float) -> float:
    return round(x, 3)


def _closer(tracks: dict, robot: str, point: tuple, best: float) -> Optional[tuple]:
    """(distance, closest_approach) when `robot` at point (t, x, y, z) is nearer than best to the latest
    point of another robot's track (at most 1 s older; one of the two above 0.3 m: two robots parked on
    the ground are not an approach), else None."""
    t, xyz = point[0], point[1:]
    found = None
    for other, otr in tracks.items():
        if other != robot and otr and abs(otr[-1][0] - t) <= 1.0 and max(xyz[2], otr[-1][3]) > 0.3:
            d = math.dist(xyz, otr[-1][1:])
            if d < best:
                best = d
                found = (d, {"robots": sorted([robot, other]), "t": round(t, 1),
                             "positions": {robot: [round(v, 2) for v in xyz],
                                           other: [round(v, 2) for v in otr[-1][1:]]}})
    return found


@dataclass
class ClosestApproach:
    """The closest approach of two robots over tracks of their latest points (one per robot)."""
    tracks: dict = field(default_factory=dict)     # robot -> [(t, x, y, z)] (the latest only)
    min_separation: float = math.inf
    closest_approach: dict = field(default_factory=dict)

    def add(self, robot: str, point: tuple) -> None:
        found = _closer(self.tracks, robot, point, self.min_separation)
        if found is not None:
            self.min_separation, self.closest_approach = found
        self.tracks[robot] = [tuple(point)]


@dataclass
class MissionRecord:
    """Everything the report needs, updated as ground truth arrives.

    Args:
        seed: seed of the trial (written as is).
        duration: trial length in sim seconds (20 minutes).
    """
    seed: int = 0
    duration: float = 1200.0
    fires: dict[str, FireRecord] = field(default_factory=dict)
    score: float = 0.0
    score_history: list[tuple[float, float]] = field(default_factory=list)
    tracks: dict[str, list[tuple[float, float, float, float]]] = field(default_factory=dict)
    crashes: list[str] = field(default_factory=list)
    min_separation: float = math.inf
    closest_approach: dict = field(default_factory=dict)   # who, when and where min_separation happened
    # the same from the simulator's true poses (add_true_pose): under GNSS error the data_feed poses are
    # off by a metre each, and two robots resting on pads 2.6 m apart are reported 0.9 m apart
    truth: "ClosestApproach" = field(default_factory=lambda: ClosestApproach())
    elapsed: float = 0.0
    robot_kinds: dict[str, str] = field(default_factory=dict)  # robot id -> "water" / "blanket" / "ugv"
    slam: SlamRecord = field(default_factory=lambda: SlamRecord(footprints=ARENA.footprints))  # indoor_flights.py
    water: dict[str, list[Pour]] = field(default_factory=dict)  # robot id -> where its water went, per holder

    def update_fire(self, fire_id: str, kind: int, floor: int, position: tuple[float, float, float],
                    active: bool, extinguished: bool, progress: float, t_ext: float,
                    litres_received: float = 0.0, litres_needed: Optional[float] = None) -> None:
        """Record one ground-truth fire state (inactive holders are not fires of the trial)."""
        if not active:
            return
        rec = self.fires.get(fire_id)
        if rec is None:
            rec = self.fires[fire_id] = FireRecord(fire_id, KIND_NAMES.get(kind, "unknown"), int(floor), position)
        rec.progress = float(progress)
        rec.litres_received, rec.litres_needed = float(litres_received), litres_needed
        if extinguished and not rec.extinguished:
            rec.extinguished = True
            rec.t_extinguished = float(t_ext) if t_ext >= 0 else self.elapsed
            rec.extinguished_by = self.nearest_robot(rec.position, rec.kind)

    def set_water(self, robot: str, pours: list[Pour]) -> None:
        """The simulator's latest account of where a robot's water went (cumulative since the start)."""
        self.water[robot] = pours

    def add_pose(self, robot: str, t: float, x: float, y: float, z: float, min_dt: float = 0.5) -> None:
        """Append to a robot's track (at most one point per `min_dt`) and track the closest approach."""
        tr = self.tracks.setdefault(robot, [])
        if tr and t - tr[-1][0] < min_dt:
            return
        tr.append((t, x, y, z))
        found = _closer(self.tracks, robot, (t, x, y, z), self.min_separation)
        if found is not None:
            self.min_separation, self.closest_approach = found

    def add_true_pose(self, robot: str, t: float, x: float, y: float, z: float) -> None:
        """A robot's true position (/sim/robots): the closest approach the summary reports."""
        self.truth.add(robot, (t, x, y, z))

    def nearest_robot(self, p: tuple[float, float, float], kind: str) -> Optional[str]:
        """The robot closest to p now: who put the fire out (blanket robots for ground fires)."""
        best = None
        for robot, tr in self.tracks.items():
            if not tr:
                continue
            rk = self.robot_kinds.get(robot, "")
            if kind == "ground" and rk and rk != "blanket":
                continue
            if kind != "ground" and rk == "blanket":
                continue
            d = math.dist(p, tr[-1][1:])
            if best is None or d < best[0]:
                best = (d, robot)
        return best[1] if best else None

    def set_score(self, t: float, score: float, crashed: list[str]) -> None:
        self.elapsed = max(self.elapsed, t)
        if not self.score_history or abs(score - self.score) > 1e-6 or t - self.score_history[-1][0] >= 5.0:
            self.score_history.append((t, score))
        self.score = score
        for c in crashed:
            if c not in self.crashes:
                self.crashes.append(c)

    def all_out(self) -> bool:
        """True when every active fire of the trial is out (and some fire is known)."""
        return bool(self.fires) and all(f.extinguished for f in self.fires.values())

    def finished(self, expected_fires: int = 0) -> Optional[str]:
        """Why the trial is over, or None: time is up, or every fire is out."""
        if self.elapsed >= self.duration:
            return "time"
        if self.all_out() and len(self.fires) >= expected_fires:
            return "all_fires_out"
        return None

    def indoor_flights(self) -> list[dict]:
        """Every indoor flight on SLAM with its pose error against the truth (empty without SLAM)."""
        return self.slam.flights(self.elapsed, ARENA.floor_of)

    def _separation(self) -> dict:
        """min_separation_m and closest_approach from the true poses when the simulator gave them (the
        data_feed ones then as min_reported_separation_m), else from the data_feeds."""
        reported = round(self.min_separation, 3) if math.isfinite(self.min_separation) else None
        if not math.isfinite(self.truth.min_separation):
            return {"min_separation_m": reported, "closest_approach": self.closest_approach or None,
                    "separation_source": "data_feed"}
        return {"min_separation_m": round(self.truth.min_separation, 3),
                "closest_approach": self.truth.closest_approach, "separation_source": "truth",
                "min_reported_separation_m": reported, "closest_reported_approach": self.closest_approach or None}

    def _robots_water(self) -> dict:
        """Per robot that pumped: litres pumped, into fires, on walls, fallen short, efficiency (into fires
        per litre pumped) and its pours (per holder pumped at)."""
        out = {}
        for robot, pours in sorted(self.water.items()):
            pumped, into = sum(p.aimed for p in pours), sum(p.entered for p in pours)
            out[robot] = {
                "litres_pumped": _litres(pumped), "litres_into_fires": _litres(into),
                "efficiency": _ratio(into, pumped), "litres_on_walls": _litres(sum(p.on_wall for p in pours)),
                "litres_fell_short": _litres(sum(p.fell_short for p in pours)),
                "pours": [{"fire": p.fire, "kind": p.kind, "litres_aimed": _litres(p.aimed),
                           "litres_in": _litres(p.entered), "litres_on_wall": _litres(p.on_wall),
                           "litres_fell_short": _litres(p.fell_short)} for p in pours]}
        return out

    def _water_efficiency(self) -> dict:
        """Per kind of fire put out with water: litres pumped at holders of that kind, litres into fires of
        that kind, and their ratio (null when none was pumped)."""
        out = {}
        for kind in WATER_KINDS:
            pours = [p for w in self.water.values() for p in w if p.kind == kind]
            pumped, into = sum(p.aimed for p in pours), sum(p.entered for p in pours)
            out[kind] = {"litres_pumped": _litres(pumped), "litres_into_fires": _litres(into),
                         "efficiency": _ratio(into, pumped)}
        return out

    def _fire_water(self, f: FireRecord) -> dict:
        """A fire's litres: received (its container), needed, pumped at it, and who poured what into it."""
        if f.kind not in WATER_KINDS:
            return {"litres_received": None}
        pours = [(robot, p) for robot, w in sorted(self.water.items()) for p in w if p.fire == f.fire_id]
        return {"litres_received": _litres(f.litres_received),
                "litres_needed": None if f.litres_needed is None else _litres(f.litres_needed),
                "litres_aimed": _litres(sum(p.aimed for _, p in pours)),
                "litres_by_robot": {robot: _litres(p.entered) for robot, p in pours if p.entered > 0.0}}

    def summary(self, wall_time: float, end_reason: str = "", extra: Optional[dict[str, Any]] = None) -> dict:
        """The summary.json object."""
        fires = sorted(self.fires.values(), key=lambda f: (f.kind, f.floor, f.fire_id))
        times = [f.t_extinguished for f in fires if f.extinguished and f.t_extinguished is not None]
        out = {
            "seed": self.seed,
            "sim_time_s": round(self.elapsed, 2),
            "wall_time_s": round(wall_time, 2),
            "real_time_factor": round(self.elapsed / wall_time, 3) if wall_time > 0 else None,
            "score": round(self.score, 3),
            "fires_extinguished": sum(1 for f in fires if f.extinguished),
            "fires_total": len(fires),
            "crashes": list(self.crashes),
            "all_out_time_s": round(max(times), 2) if self.all_out() and times else None,
            **self._separation(),
            "end_reason": end_reason,
            "fires": [{"id": f.fire_id, "kind": f.kind, "floor": f.floor, "extinguished_by": f.extinguished_by,
                       "t_extinguished": None if f.t_extinguished is None else round(f.t_extinguished, 2),
                       "progress": round(f.progress, 3), "position": [round(v, 2) for v in f.position],
                       **self._fire_water(f)}
                      for f in fires],
            "robots": self._robots_water(),
            "water_efficiency": self._water_efficiency(),
            "indoor_flights": self.indoor_flights(),
        }
        out.update(extra or {})
        return out


def check_summary(s: dict) -> list[str]:
    """What a summary.json lacks (empty when complete); used by the mission test and the benchmark."""
    missing = [k for k in SUMMARY_KEYS if k not in s]
    for i, f in enumerate(s.get("fires", [])):
        missing += [f"fires[{i}].{k}" for k in FIRE_KEYS if k not in f]
        if f.get("kind") not in ("ground", "facade", "indoor"):
            missing.append(f"fires[{i}].kind={f.get('kind')}")
    return missing
