"""Static world of Challenge 3: arena, building boxes, fire holders and robot homes, plus a vectorised ray caster.

Everything is axis-aligned boxes so that ray casting is a NumPy slab test over (rays x boxes); walls with
windows and doors are split into solid boxes once, at load time. No ROS here: hector_mapping's tests and
benchmarks build laser scans of indoor flights with `World.laser_scan`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Optional, Sequence

import numpy as np
import yaml
from mbzirc_arena.arena import floor_of

from . import constants as C

DEFAULT_WORLD = Path(__file__).resolve().parent / "worlds" / "c3_default.yaml"
GROUND = -1   # raycast hit index of the ground plane z = 0
NO_HIT = -2   # raycast hit index of nothing within range
_DEFAULT_COLOR = (200, 190, 170)


class WorldError(ValueError):
    """A world file that cannot be used; the message says which entry and why."""


@dataclass
class Holder:
    """A place where a fire may be: facade/indoor hole on a wall face, or a ground plate."""
    id: str
    kind: str                 # "facade" | "indoor" | "ground"
    position: np.ndarray      # (3,) hole centre on the outer face, or plate centre
    normal: np.ndarray        # (3,) outward unit normal (+z for ground)
    floor: int


@dataclass
class RobotSpec:
    """A robot of the world file: id 0 is the UGV, 1..N UAVs."""
    id: int
    kind: str                 # "uav" | "ugv"
    payload: str              # "water" | "blanket"
    home: np.ndarray          # (3,)
    yaw: float = 0.0


@dataclass
class World:
    """Solid boxes (after splitting walls around their openings), holders, robots, arena bounds."""
    name: str
    arena_min: np.ndarray
    arena_max: np.ndarray
    bmin: np.ndarray          # (B, 3)
    bmax: np.ndarray          # (B, 3)
    box_names: list
    box_temp: np.ndarray      # (B,) deg C
    box_color: np.ndarray     # (B, 3) uint8 RGB
    facade_holders: list
    indoor_holders: list
    ground_holders: list
    robots: list
    active: dict
    floors: list = field(default_factory=lambda: [0.0, 5.0, 10.0])
    active_ids: Optional[list] = None   # explicit active holder ids (overrides the seed's choice)
    trial_duration: float = C.TRIAL_DURATION
    box_building: list = field(default_factory=list)   # (B,) building tag of each box ("" = the simulator's)
    uncertainty: dict = field(default_factory=dict)    # the world file's `uncertainty:` profiles (uncertainty.py)

    # ------------------------------------------------------------------ queries
    def inside_arena(self, p: Sequence[float], margin: float = 0.0) -> bool:
        """True when p (x, y, z) is finite and inside the arena box shrunk by margin."""
        p = np.asarray(p, dtype=float)
        return bool(np.all(np.isfinite(p)) and np.all(p >= self.arena_min + margin)
                    and np.all(p <= self.arena_max - margin))

    def floor_of(self, z: float) -> int:
        """Index of the tower level of height z (the arena's rule, mbzirc_arena `floor_of`)."""
        return floor_of(z, self.floors)

    def support_height(self, x: float, y: float, z: float) -> float:
        """Height of the surface a robot at (x, y, z) would land on: the highest box top at or below z."""
        inside = ((self.bmin[:, 0] <= x) & (x <= self.bmax[:, 0]) & (self.bmin[:, 1] <= y)
                  & (y <= self.bmax[:, 1]) & (self.bmax[:, 2] <= z + 0.05))
        return float(self.bmax[inside, 2].max()) if inside.any() else 0.0

    def sphere_hits_building(self, centres: np.ndarray, radius: float | np.ndarray) -> np.ndarray:
        """(N,) bool: sphere i of the given centre(s) and radius overlaps a building box."""
        c = np.atleast_2d(np.asarray(centres, dtype=float))
        d = np.maximum(np.maximum(self.bmin[None] - c[:, None], 0.0), c[:, None] - self.bmax[None])
        dist2 = np.einsum("nbk,nbk->nb", d, d)
        r = np.broadcast_to(np.asarray(radius, dtype=float), (c.shape[0],))
        return (dist2 < (r[:, None] ** 2)).any(axis=1)

    def boxes_in_cone(self, p: np.ndarray, axis: np.ndarray, half_angle: float, radius: float) -> np.ndarray:
        """Indices of boxes that may intersect a viewing cone (apex p, unit axis, half angle, length radius).

        Bounding-sphere test, conservative: used to cull what a camera cannot see before ray casting.
        """
        c = 0.5 * (self.bmin + self.bmax)
        rb = 0.5 * np.linalg.norm(self.bmax - self.bmin, axis=1)
        v = c - p
        dist = np.linalg.norm(v, axis=1)
        along = v @ axis
        # angle of the centre off-axis minus the angle the sphere subtends
        cos_off = np.where(dist > 1e-9, along / np.maximum(dist, 1e-9), 1.0)
        off = np.arccos(np.clip(cos_off, -1.0, 1.0))
        sub = np.arcsin(np.clip(rb / np.maximum(dist, 1e-9), 0.0, 1.0))
        keep = (dist <= rb) | ((off - sub <= half_angle) & (dist - rb <= radius))
        return np.nonzero(keep)[0]

    def boxes_in_frustum(self, apex: np.ndarray, normals: np.ndarray, far: float) -> np.ndarray:
        """Indices of boxes not entirely outside a pyramid (apex, inward side-plane normals (K, 3)) within far.

        Exact for the side planes (a box is dropped when its most inward corner is behind one plane), which
        is what makes the narrow thermal camera cheap next to large facade boxes.
        """
        c = 0.5 * (self.bmin + self.bmax) - apex
        h = 0.5 * (self.bmax - self.bmin)
        reach = c @ normals.T + h @ np.abs(normals).T          # (B, K) max of n . corner
        d = np.maximum(np.maximum(self.bmin - apex, 0.0), apex - self.bmax)
        near = np.einsum("bk,bk->b", d, d) <= far * far
        return np.nonzero(near & (reach >= 0.0).all(axis=1))[0]

    def boxes_near(self, p: Sequence[float], radius: float) -> np.ndarray:
        """Indices of boxes whose closest point is within radius of p (culling for sensors)."""
        p = np.asarray(p, dtype=float)
        d = np.maximum(np.maximum(self.bmin - p, 0.0), p - self.bmax)
        return np.nonzero(np.einsum("bk,bk->b", d, d) <= radius * radius)[0]

    # ------------------------------------------------------------------ ray casting
    def raycast(self, origins: np.ndarray, dirs: np.ndarray, max_range: float,
                boxes: Optional[np.ndarray] = None, ground: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """Cast rays (origins (R,3) or (3,), unit dirs (R,3)) against the boxes and the ground plane z = 0.

        Returns (t, idx): distance of the first hit (inf when none within max_range) and the index of
        the box hit (GROUND for the ground, NO_HIT for nothing). `boxes` restricts the test to a subset
        (indices), which is how sensors cull what is out of range.
        """
        d = np.asarray(dirs, dtype=float)
        o_in = np.asarray(origins, dtype=float)
        o = np.broadcast_to(o_in, d.shape)
        idx_all = np.arange(len(self.bmin)) if boxes is None else np.asarray(boxes, dtype=int)
        t, local = slab_raycast(o_in if o_in.ndim == 1 else o, d, self.bmin[idx_all], self.bmax[idx_all])
        idx = np.where(local >= 0, idx_all[np.maximum(local, 0)] if len(idx_all) else -2, NO_HIT)
        if ground:
            with np.errstate(divide="ignore", invalid="ignore"):
                tg = np.where(d[:, 2] < -1e-9, -o[:, 2] / d[:, 2], np.inf)
            tg = np.where(tg >= 0.0, tg, np.inf)
            g = tg < t
            t = np.where(g, tg, t)
            idx = np.where(g, GROUND, idx)
        far = t > max_range
        t = np.where(far, np.inf, t)
        idx = np.where(far, NO_HIT, idx)
        return t, idx

    def laser_scan(self, x: float, y: float, z: float, yaw: float, n_beams: int = C.LASER_BEAMS,
                   range_min: float = C.LASER_RANGE_MIN, range_max: float = C.LASER_RANGE_MAX) -> np.ndarray:
        """Ranges of a horizontal 2D laser at (x, y, z) with heading yaw.

        Beam i points at yaw + angle_min + i * 2 pi / n with angle_min = -pi, so the front beam is
        index n / 2 (the RPLidar convention of interfaces.md). No hit within range_max -> inf; a hit
        closer than range_min is reported as range_min. Only boxes spanning height z are tested (2D slab).
        """
        sel = np.nonzero((self.bmin[:, 2] <= z) & (z <= self.bmax[:, 2]))[0]
        if len(sel):
            p = np.array([x, y])
            dd = np.maximum(np.maximum(self.bmin[sel, :2] - p, 0.0), p - self.bmax[sel, :2])
            sel = sel[np.einsum("bk,bk->b", dd, dd) <= range_max * range_max]
        ang = yaw + beam_angles(n_beams)
        d2 = np.stack([np.cos(ang), np.sin(ang)], axis=1)
        if len(sel) == 0:
            return np.full(n_beams, np.inf)
        t, _ = slab_raycast(np.array([x, y], float), d2, self.bmin[sel, :2], self.bmax[sel, :2])
        t = np.where(t > range_max, np.inf, t)
        return np.where(t < range_min, range_min, t)


def beam_angles(n_beams: int = C.LASER_BEAMS) -> np.ndarray:
    """Beam angles relative to the laser heading: angle_min = -pi, increment 2 pi / n."""
    return -math.pi + np.arange(n_beams) * (2.0 * math.pi / n_beams)


def slab_raycast(o: np.ndarray, d: np.ndarray, bmin: np.ndarray, bmax: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised slab test of R rays against B axis-aligned boxes ((B, D)), any dimension D.

    o: one origin (D,) shared by all rays (the fast path sensors use) or one per ray (R, D); d: (R, D).
    Returns (t, idx): first non-negative hit distance per ray (inf if none, float64 holding float32
    precision) and the box index (-1 if none). A ray starting inside a box hits it at t = 0.
    """
    R = d.shape[0]
    if bmin.shape[0] == 0:
        return np.full(R, np.inf), np.full(R, -1, dtype=int)
    # float32: several times faster on these (R, B) arrays (memory bound), and a LaserScan carries float32
    # ranges anyway; the error is about 1e-6 relative (micrometres at sensor ranges)
    o, d = o.astype(np.float32), d.astype(np.float32)
    bmin, bmax = bmin.astype(np.float32), bmax.astype(np.float32)
    shared = o.ndim == 1
    tnear = tfar = None
    # One axis at a time on (R, B) arrays: reductions over a tiny last axis are slow in NumPy.
    for k in range(d.shape[1]):
        dk = d[:, k]
        inv = np.float32(1.0) / np.where(np.abs(dk) < 1e-12, np.float32(1e-12), dk)
        if shared:
            a = np.multiply.outer(inv, bmin[:, k] - o[k])
            b = np.multiply.outer(inv, bmax[:, k] - o[k])
        else:
            a = np.multiply.outer(inv, bmin[:, k]) - (o[:, k] * inv)[:, None]
            b = np.multiply.outer(inv, bmax[:, k]) - (o[:, k] * inv)[:, None]
        lo = np.minimum(a, b)
        hi = np.maximum(a, b, out=a)
        if tnear is None:
            tnear, tfar = lo, hi
        else:
            np.maximum(tnear, lo, out=tnear)
            np.minimum(tfar, hi, out=tfar)
    miss = tnear > tfar
    miss |= tfar < 0.0
    np.maximum(tnear, 0.0, out=tnear)
    tnear[miss] = np.inf
    idx = tnear.argmin(axis=1)
    t = tnear[np.arange(R), idx].astype(np.float64)
    return t, np.where(np.isfinite(t), idx, -1)


# ---------------------------------------------------------------------- loading
def _vec(entry: dict, key: str, n: int, where: str, default: Any = None) -> np.ndarray:
    """Read a finite numeric vector of length n, or raise WorldError naming the entry."""
    if key not in entry:
        if default is not None:
            return np.asarray(default, dtype=float)
        raise WorldError(f"{where}: missing '{key}'")
    try:
        v = np.asarray(entry[key], dtype=float)
    except (TypeError, ValueError) as e:
        raise WorldError(f"{where}: '{key}' must be {n} numbers, got {entry[key]!r}") from e
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise WorldError(f"{where}: '{key}' must be {n} finite numbers, got {entry[key]!r}")
    return v


def split_wall(bmin: np.ndarray, bmax: np.ndarray, openings: list, where: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """Split a wall box into solid boxes around rectangular openings (along its long axis x or y, and z).

    Cells of the grid made by the opening edges are solid unless inside an opening; solid cells are
    merged into vertical runs per column, and equal neighbouring columns are merged.
    """
    axis = 0 if (bmax[0] - bmin[0]) >= (bmax[1] - bmin[1]) else 1
    ops = []
    for k, op in enumerate(openings or []):
        w = f"{where} opening {k}"
        if not isinstance(op, dict):
            raise WorldError(f"{w}: must be a mapping with 'along' and 'z'")
        a = _vec(op, "along", 2, w)
        z = _vec(op, "z", 2, w)
        if a[0] >= a[1] or z[0] >= z[1]:
            raise WorldError(f"{w}: ranges must be increasing, got along {a.tolist()} z {z.tolist()}")
        ops.append((max(a[0], bmin[axis]), min(a[1], bmax[axis]), max(z[0], bmin[2]), min(z[1], bmax[2])))
    ops = [o for o in ops if o[0] < o[1] and o[2] < o[3]]
    if not ops:
        return [(bmin.copy(), bmax.copy())]
    sb = sorted({bmin[axis], bmax[axis], *[o[0] for o in ops], *[o[1] for o in ops]})
    zb = sorted({bmin[2], bmax[2], *[o[2] for o in ops], *[o[3] for o in ops]})

    def solid(s0, s1, z0, z1) -> bool:
        sm, zm = 0.5 * (s0 + s1), 0.5 * (z0 + z1)
        return not any(o[0] < sm < o[1] and o[2] < zm < o[3] for o in ops)

    def strips(outer, inner, cell):
        """Runs of solid cells along `inner` for every interval of `outer`, equal neighbours merged."""
        out = []
        for a0, a1 in zip(outer[:-1], outer[1:]):
            runs, start = [], None
            for b0, b1 in zip(inner[:-1], inner[1:]):
                ok = cell(a0, a1, b0, b1)
                if ok and start is None:
                    start = b0
                if not ok and start is not None:
                    runs.append((start, b0))
                    start = None
            if start is not None:
                runs.append((start, inner[-1]))
            if out and out[-1][2] == runs and abs(out[-1][1] - a0) < 1e-9:
                out[-1][1] = a1
            else:
                out.append([a0, a1, runs])
        return out

    # vertical strips (columns along the wall) or horizontal bands, whichever gives fewer boxes
    cols = strips(sb, zb, lambda s0, s1, z0, z1: solid(s0, s1, z0, z1))
    bands = strips(zb, sb, lambda z0, z1, s0, s1: solid(s0, s1, z0, z1))
    out = []
    if sum(len(c[2]) for c in cols) <= sum(len(b[2]) for b in bands):
        for s0, s1, runs in cols:
            for z0, z1 in runs:
                lo, hi = bmin.copy(), bmax.copy()
                lo[axis], hi[axis], lo[2], hi[2] = s0, s1, z0, z1
                out.append((lo, hi))
    else:
        for z0, z1, runs in bands:
            for s0, s1 in runs:
                lo, hi = bmin.copy(), bmax.copy()
                lo[axis], hi[axis], lo[2], hi[2] = s0, s1, z0, z1
                out.append((lo, hi))
    return out


def _holders(raw: Any, kind: str, floors: list) -> list[Holder]:
    if raw is None:
        return []
    if not isinstance(raw, list):
        raise WorldError(f"{kind}_holders: must be a list")
    out = []
    for i, h in enumerate(raw):
        w = f"{kind}_holders[{i}]"
        if not isinstance(h, dict):
            raise WorldError(f"{w}: must be a mapping")
        pos = _vec(h, "position", 3, w)
        n = _vec(h, "normal", 3, w, default=[0.0, 0.0, 1.0])
        if np.linalg.norm(n) < 1e-9:
            raise WorldError(f"{w}: normal must not be zero")
        floor = int(h.get("floor", floor_of(pos[2], floors) if kind != "ground" else 0))
        out.append(Holder(str(h.get("id", f"{kind}_{i}")), kind, pos, n / np.linalg.norm(n), floor))
    return out


def parse_world(data: Any, n_uavs: Optional[int] = None, ugv: bool = True) -> World:
    """Build a World from the parsed YAML mapping (see worlds/c3_default.yaml for the format).

    n_uavs: keep UAVs 1..n_uavs; UAVs the file does not list get water payloads and homes on a 2 m grid
    near the origin. ugv: keep or drop robot 0.
    """
    if not isinstance(data, dict):
        raise WorldError("world file: top level must be a mapping")
    arena = data.get("arena")
    if not isinstance(arena, dict):
        raise WorldError("arena: missing mapping with 'min' and 'max'")
    amin, amax = _vec(arena, "min", 3, "arena"), _vec(arena, "max", 3, "arena")
    if np.any(amin >= amax):
        raise WorldError("arena: min must be below max on every axis")
    floors = data.get("floors", [0.0, 5.0, 10.0])
    try:
        floors = [float(f) for f in floors]
    except (TypeError, ValueError) as e:
        raise WorldError("floors: must be a list of heights") from e
    lo, hi, names, temps, colors, tags = [], [], [], [], [], []
    for section in ("walls", "boxes"):
        raw = data.get(section) or []
        if not isinstance(raw, list):
            raise WorldError(f"{section}: must be a list")
        for i, b in enumerate(raw):
            w = f"{section}[{i}]"
            if not isinstance(b, dict):
                raise WorldError(f"{w}: must be a mapping")
            b0, b1 = _vec(b, "min", 3, w), _vec(b, "max", 3, w)
            if np.any(b0 >= b1):
                raise WorldError(f"{w} ({b.get('name', '?')}): min must be below max on every axis")
            temp = float(b.get("temp", C.INDOOR_WALL_TEMP))
            color = _vec(b, "color", 3, w, default=_DEFAULT_COLOR)
            parts = split_wall(b0, b1, b.get("openings"), w) if section == "walls" else [(b0, b1)]
            for p0, p1 in parts:
                lo.append(p0)
                hi.append(p1)
                names.append(str(b.get("name", f"{section}_{i}")))
                temps.append(temp)
                colors.append(color)
                tags.append(str(b.get("building", "") or ""))
    robots = []
    raw_robots = data.get("robots") or []
    if not isinstance(raw_robots, list):
        raise WorldError("robots: must be a list")
    for i, r in enumerate(raw_robots):
        w = f"robots[{i}]"
        if not isinstance(r, dict) or "id" not in r:
            raise WorldError(f"{w}: must be a mapping with an 'id'")
        try:
            rid = int(r["id"])
        except (TypeError, ValueError) as e:
            raise WorldError(f"{w}: id must be an integer") from e
        kind = str(r.get("kind", "ugv" if rid == C.UGV_ID else "uav"))
        payload = str(r.get("payload", C.PAYLOAD_WATER))
        if kind not in ("uav", "ugv") or payload not in (C.PAYLOAD_WATER, C.PAYLOAD_BLANKET):
            raise WorldError(f"{w}: kind must be uav|ugv and payload water|blanket")
        robots.append(RobotSpec(rid, kind, payload, _vec(r, "home", 3, w), float(r.get("yaw", 0.0))))
    if len({r.id for r in robots}) != len(robots):
        raise WorldError("robots: ids must be unique")
    if n_uavs is not None:
        robots = [r for r in robots if r.kind == "ugv" or r.id <= n_uavs]
        have = {r.id for r in robots}
        k = 0
        for rid in range(1, n_uavs + 1):
            if rid in have:
                continue
            while True:  # next free grid cell south-west of the default homes
                home = np.array([-14.0 + 2.0 * (k % 14), -11.0 + 2.0 * (k // 14), 0.0])
                k += 1
                if all(np.linalg.norm(home[:2] - r.home[:2]) > 1.9 for r in robots):
                    break
            robots.append(RobotSpec(rid, "uav", C.PAYLOAD_WATER, home, 0.0))
    if not ugv:
        robots = [r for r in robots if r.kind != "ugv"]
    robots.sort(key=lambda r: r.id)
    active = data.get("active") or {}
    if not isinstance(active, dict):
        raise WorldError("active: must be a mapping")
    active_ids = active.pop("ids", None)
    if active_ids is not None and not isinstance(active_ids, list):
        raise WorldError("active.ids: must be a list of holder ids")
    world = World(
        name=str(data.get("name", "unnamed")), arena_min=amin, arena_max=amax,
        bmin=np.array(lo, dtype=float).reshape(-1, 3), bmax=np.array(hi, dtype=float).reshape(-1, 3),
        box_names=names, box_temp=np.array(temps, dtype=float),
        box_color=np.array(colors, dtype=float).reshape(-1, 3).clip(0, 255).astype(np.uint8),
        facade_holders=_holders(data.get("facade_holders"), "facade", floors),
        indoor_holders=_holders(data.get("indoor_holders"), "indoor", floors),
        ground_holders=_holders(data.get("ground_holders"), "ground", floors),
        robots=robots, active={k: int(v) for k, v in active.items()}, floors=floors,
        active_ids=[str(i) for i in active_ids] if active_ids is not None else None,
        trial_duration=float(data.get("trial_duration", C.TRIAL_DURATION)), box_building=tags,
        uncertainty=data.get("uncertainty") or {})
    if world.active_ids is not None:
        known = {h.id for h in world.facade_holders + world.indoor_holders + world.ground_holders}
        unknown = sorted(set(world.active_ids) - known)
        if unknown:
            raise WorldError(f"active.ids: unknown holder ids {unknown}")
    for r in robots:
        if not world.inside_arena(r.home):
            raise WorldError(f"robot {r.id}: home {r.home.tolist()} is outside the arena")
    return world


def load_world(path: Optional[str | Path] = None, n_uavs: Optional[int] = None, ugv: bool = True) -> World:
    """Load a YAML world file (the default competition layout when path is None or empty).

    Raises WorldError with a readable message for unreadable or malformed files.
    """
    p = Path(path) if path else DEFAULT_WORLD
    try:
        text = p.read_text()
    except OSError as e:
        raise WorldError(f"cannot read world file {p}: {e}") from e
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as e:
        raise WorldError(f"world file {p} is not valid YAML: {e}") from e
    try:
        return parse_world(data, n_uavs=n_uavs, ugv=ugv)
    except WorldError as e:
        raise WorldError(f"world file {p}: {e}") from e
