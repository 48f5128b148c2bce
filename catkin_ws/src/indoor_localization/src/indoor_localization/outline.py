"""Refining the GNSS anchor by the building's known outline, seen in the laser scan (no ROS).

The anchor (anchor.py) inherits the GNSS error of the last fixes before entering, about a metre. A team
knows the outer walls before the trial (the buildings' outline, mbzirc_arena), and the laser sees them: the
facade from outside in front of a window, the outer walls' inner faces from inside. So each processed scan
is put in the arena frame by the anchor (and the correction found so far), and for every outline wall the
robot can see from where it is, the returns near that wall's line are fitted with a line (robust: trimmed
total least squares). A line supported by enough returns spread along the wall is one observation: its
offset along the wall's normal and its direction. Every observation is kept in the SLAM map frame (which
hector_mapping keeps consistent indoors and near the building), so the correction is fitted again, on all
of them, against the anchor of the moment (outdoors the anchor follows GNSS; indoors it is frozen);
outdoors only the last seconds' observations are kept (`forget_before`), as for the anchor.

The correction is a small rigid 2D transform on the arena side (refined = correction o anchor), found by
Gauss-Newton on: each wall's offset (constrains the translation along that wall's normal only), each wall's
direction (the yaw), and a weak prior (nothing moves without evidence). The outer walls' thickness is not
known (not in the arena model): it is a fourth unknown, seen in a wall's inner face only, and fixed by the
facade seen from outside plus an inner face, or by two opposite inner faces. Whatever the prior leaves
uncertain (the posterior std along a direction above `max_std`: one wall only, or only inner faces and an
unknown thickness) is not corrected: each direction is corrected only once observed.

Interior walls are sensed too; only returns close to a predicted outline line count (the gate is wide
while the wall's offset is unknown, narrow once it is observed), a line must match the wall's direction,
and a wall whose observations disagree with the fit of the others is dropped from it.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, replace
from typing import Optional, Sequence

import numpy as np

from mbzirc_arena.buildings import dist_point_segment
from mbzirc_arena.yaw import wrap_angle

from .anchor import Anchor, compose

IDENTITY = Anchor(0.0, 0.0, 0.0)
COVERAGE_BIN = 0.25          # m: bins along a wall line when measuring how the returns spread along it
CORNER_TOUCH = 0.05          # m: a face's end this near another building's face is no corner of the outline
SURFACE_BIN = 0.1            # m: bands parallel to a wall when looking for its outermost surface
SURFACE_DEPTH = 0.6          # m: returns this far in from the outermost surface may belong to it (a wall
                             # tilted by the anchor's yaw error spreads over a band this deep)


def wrap_half(a):
    """Angle of an undirected line in [-pi/2, pi/2)."""
    return (np.asarray(a) + 0.5 * math.pi) % math.pi - 0.5 * math.pi


@dataclass(frozen=True)
class Face:
    """One outer wall of a building: its outer face from a to b, outward unit normal, normal . p = offset."""
    building: int
    name: str
    a: tuple
    b: tuple
    normal: tuple
    offset: float
    top: float                   # m: the wall stands up to its building's roof
    end: bool = False            # a corner's virtual face: across a wall's line through its end (`corner_ends`)

    @property
    def direction(self) -> float:
        """Angle of the wall's line (undirected)."""
        return float(wrap_half(math.atan2(self.b[1] - self.a[1], self.b[0] - self.a[0])))

    @property
    def length(self) -> float:
        return math.hypot(self.b[0] - self.a[0], self.b[1] - self.a[1])


def outline_faces(footprints: Sequence[Sequence[float]]) -> list:
    """The four outer faces of every footprint (x_min, y_min, x_max, y_max, top), as mbzirc_arena gives
    them (`Arena.footprints`)."""
    faces = []
    for k, (x0, y0, x1, y1, top) in enumerate(footprints):
        faces += [Face(k, "west", (x0, y0), (x0, y1), (-1.0, 0.0), -x0, top),
                  Face(k, "east", (x1, y0), (x1, y1), (1.0, 0.0), x1, top),
                  Face(k, "south", (x0, y0), (x1, y0), (0.0, -1.0), -y0, top),
                  Face(k, "north", (x0, y1), (x1, y1), (0.0, 1.0), y1, top)]
    return faces


def corner_ends(faces: Sequence[Face]) -> dict:
    """{(face index, 0 or 1): virtual Face} for the ends (a, b) of every face that are corners of the whole
    outline: no face of another building touches them (where the extension meets the tower, facade A's line
    goes on along the extension's: no corner there). The virtual face lies across the wall's line through
    the end, its normal along the wall, outwards past the end: an end seen is an offset of that face."""
    out = {}
    for k, f in enumerate(faces):
        for i, (e, other) in enumerate(((f.a, f.b), (f.b, f.a))):
            if any(g.building != f.building and dist_point_segment(e, g.a, g.b) <= CORNER_TOUCH for g in faces):
                continue
            ux, uy = e[0] - other[0], e[1] - other[1]
            n = math.hypot(ux, uy)
            if n < 1e-6:
                continue
            ux, uy = ux / n, uy / n
            out[(k, i)] = Face(f.building, f"{f.name} {'a' if i == 0 else 'b'} end", e, e, (ux, uy),
                               ux * e[0] + uy * e[1], f.top, end=True)
    return out


def theil_sen(u: np.ndarray, v: np.ndarray, samples: int = 40) -> np.ndarray:
    """v's robust straight-line fit against u (median of pairwise slopes over an even subsample),
    evaluated at u."""
    idx = np.linspace(0, len(u) - 1, min(samples, len(u))).astype(int)
    us, vs = u[idx], v[idx]
    i, j = np.triu_indices(len(idx), 1)
    du = us[j] - us[i]
    ok = np.abs(du) > 1e-6
    slope = float(np.median((vs[j] - vs[i])[ok] / du[ok])) if ok.any() else 0.0
    return slope * u + float(np.median(v - slope * u))


def transform(points: np.ndarray, theta: float, tx: float, ty: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.column_stack((c * points[:, 0] - s * points[:, 1] + tx, s * points[:, 0] + c * points[:, 1] + ty))


@dataclass(frozen=True)
class RefineParams:
    gate_unobserved: float = 1.5     # m around an inner face's predicted line while its offset is not
                                     # observed (metre-class GNSS error; interior walls stand further in)
    gate_unobserved_outside: float = 2.5  # m likewise for an outer face seen from outside (nothing stands
                                     # between it and the robot: a wider gate catches a larger GNSS error)
    gate: float = 0.3                # m once observed (plus 3 std of the prediction)
    side_gate: float = 1.2           # m: a robot this close to a wall's line may be on either side of it
    look_beyond: float = 3.0         # m beyond a wall's predicted line where no surface may stand
    corner_ends: bool = True         # outside, a face's end at a corner of the outline is observed too
    end_max_range: float = 15.0      # m: an end farther from the robot is not observed (range, beam spacing)
    end_coverage: float = 0.75       # share of the last metre's 0.25 m stretches holding returns up to an end
    surface_points: int = 5          # returns in a band parallel to a wall that make a surface ...
    surface_spread: float = 1.0      # m ... spread over this much of its length (not a window's reveal)
    min_points: int = 15             # returns supporting a wall line
    min_span: float = 1.5            # m of wall the supporting returns must spread over ...
    min_coverage: float = 0.5        # ... with returns in this share of its 0.25 m stretches
    max_line_rms: float = 0.15       # m: a noisier line is not a wall
    max_line_angle: float = 0.2      # rad between a line and its wall (anchor's yaw error included)
    wall_sigma: float = 0.05         # m: a wall's offset as observed (SLAM, flatness), however many scans
    angle_sigma: float = 0.02        # rad: likewise its direction
    prior_sigma: float = 1.5         # m: the GNSS error the anchor may carry
    yaw_prior_sigma: float = 0.1     # rad
    thickness: float = 0.25          # m: prior of the outer walls' thickness (not in the arena model) ...
    thickness_sigma: float = 0.25    # m ... and its std (set small if it is known)
    thickness_std_floor: float = 0.03  # m: a thickness learned from the robot's own fits is never trusted more
    thickness_min: float = 0.05      # m: a fit whose walls are thinner ...
    thickness_max: float = 0.6       # m ... or thicker mixes observations that disagree: rejected
    indoor_takeover: bool = True     # without GNSS, the walls seen without it correct alone once they suffice
    max_std: float = 0.1             # m: a direction is corrected once the correction's std along it is below
    max_yaw_std: float = 0.03        # rad: likewise the yaw
    max_correction: float = 3.0      # m: a larger fitted correction is rejected
    max_yaw_correction: float = 0.15  # rad
    max_wall_residual: float = 0.25  # m: a wall whose observations the fit misses by more is dropped
    observations_per_wall: int = 20  # the latest ones kept per wall and side


@dataclass(frozen=True)
class WallObservation:
    """A wall line seen in one scan, in the SLAM map frame."""
    t: float
    face: int                        # index into the faces
    inner: bool                      # its inner face (seen from inside) or its outer face
    centroid: tuple                  # map frame
    angle: float                     # map frame, undirected
    points: int
    sigma_offset: float              # m: the line's offset std from its returns
    sigma_angle: float               # rad
    gnss: bool = True                # made while the robot had a GNSS fix (outside)


@dataclass(frozen=True)
class Correction:
    """correction (an Anchor: arena-side rigid transform), the fit's state for logs and gates."""
    transform: Anchor
    thickness: float
    observed: int                    # translation directions corrected: 0, 1 or 2
    yaw_observed: bool
    walls: int                       # walls (face, side) in the fit
    cov: np.ndarray = field(repr=False, default=None)   # (dx, dy, dyaw, thickness) at `pivot`
    pivot: tuple = (0.0, 0.0)
    crossing: bool = False           # fitted on observations made both with and without GNSS


class OutlineRefiner:
    """Feed it scans with the SLAM pose at their stamp and the anchor of the moment; `correction` is the
    refinement to compose on the anchor. `events` says what a node should log."""

    def __init__(self, faces: Sequence[Face], params: RefineParams = RefineParams()):
        self.faces = [f for f in faces if not f.end]
        self.p = params
        self.ends: dict = {}             # (face, 0 or 1) -> index of its corner end's virtual face in faces
        if params.corner_ends:
            for key, virtual in corner_ends(self.faces).items():
                self.ends[key] = len(self.faces)
                self.faces.append(virtual)
        self.walls: dict = {}            # (face, inner) -> deque of WallObservation
        self.dropped: set = set()        # walls the last fit dropped as inconsistent
        # the outer walls' thickness is the building's, not the map's: what the fits learned of it outlives
        # the observations that taught it (forgotten outdoors, cleared with a new map) as the prior
        self.thickness_prior = (params.thickness, params.thickness_sigma)
        self.gnss_valid = True           # as of the last scan
        self.range_max = math.inf        # the last scan's laser reach
        self.correction = self._no_correction()
        self.events: list = []

    def _no_correction(self) -> Correction:
        p = self.p
        thickness, sigma = self.thickness_prior
        return Correction(IDENTITY, thickness, 0, False, 0,
                          np.diag([p.prior_sigma ** 2] * 2 + [p.yaw_prior_sigma ** 2, sigma ** 2]))

    def _learn_thickness(self) -> None:
        """Keep the fitted thickness as the prior when the fit knows it better than the prior does (before
        its observations go). Rule: a thickness is learned only from a fit that observed it, never below
        `thickness_std_floor` (the fit's std counts the prior it started from too), nor from a fit across a
        crossing (observations with and without GNSS: a slip of hector_mapping's pose in the window goes
        into the thickness: 0.6 m of slip made walls 0.85 m thick), and a learned one seen by the inner face
        alone turns that face into an offset observation: inside, the walls seen from inside fix the
        translation without the facade seen from outside before the crossing. A fit whose thickness is
        beyond `thickness_min`-`thickness_max` is not accepted at all (`_accept`): realistic seed 113 at rtf
        4, outside on GNSS after two new maps, fits of walls 1.4-1.6 m thick were learned and held a UAV's
        three floor-1 flights 0.15-0.19 m off."""
        cov = self.correction.cov
        if cov is None or not self.walls or self.correction.crossing:
            return
        std = math.sqrt(max(float(cov[3, 3]), 0.0))
        if std < self.thickness_prior[1]:
            self.thickness_prior = (self.correction.thickness, max(std, self.p.thickness_std_floor))

    def forget_before(self, t: float, anchor: Anchor, refit: bool = True) -> bool:
        """Drop the observations made before t; True when some were. Outdoors, where hector_mapping's pose
        may wander far from anything (its README, "Known limitations"), only the last seconds before
        entering count, as for the anchor; indoors nothing is forgotten (the walls are seen again and again,
        the last ones kept). refit False: the caller fits next (`on_scan`, or `refit`)."""
        before = sum(len(q) for q in self.walls.values())
        if any(q and q[0].t < t for q in self.walls.values()):
            self._learn_thickness()
        for key in list(self.walls):
            q = self.walls[key]
            while q and q[0].t < t:
                q.popleft()
            if not q:
                del self.walls[key]
        dropped = sum(len(q) for q in self.walls.values()) < before
        if not self.walls:
            self.correction = self._no_correction()
        elif dropped and refit:
            self._fit(anchor)
        return dropped

    def refit(self, anchor: Anchor) -> None:
        """Fit the correction again on the kept observations against `anchor`."""
        if self.walls:
            self._fit(anchor)

    def reset(self) -> None:
        """The SLAM map frame changed (a jump, a new map): the kept observations no longer hold (what they
        taught of the walls' thickness does)."""
        self._learn_thickness()
        self.walls.clear()
        self.dropped.clear()
        self.correction = self._no_correction()

    # ---------------------------------------------------------------- one scan
    def on_scan(self, t: float, pose: tuple, z: float, anchor: Anchor, points: np.ndarray,
                laser_offset: tuple = (0.0, 0.0), gnss_valid: bool = True, range_max: float = math.inf) -> list:
        """pose: the SLAM pose (x, y, yaw) at the scan's stamp (map frame); z: the laser's height in the
        arena; points: (N, 2) returns in the laser frame; gnss_valid: the robot has a fix (outside);
        range_max: the laser's (no end is seen where its reach ends). Returns the wall observations it made
        (and keeps them); fits the correction again when there is one."""
        self.gnss_valid = gnss_valid
        self.range_max = range_max if range_max > 0 else math.inf
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        origin = (x + c * laser_offset[0] - s * laser_offset[1], y + s * laser_offset[0] + c * laser_offset[1])
        in_map = transform(points, yaw, *origin) if len(points) else np.zeros((0, 2))
        refined = compose(self.correction.transform, anchor)
        robot = refined.apply(origin[0], origin[1], 0.0)[:2]
        pts = transform(in_map, refined.theta, refined.tx, refined.ty)
        found = []
        for k, inner in self._visible_faces(robot, z):
            seen = self._observe(t, k, inner, pts, in_map, refined)
            if seen is None:
                continue
            obs, inliers = seen
            made = [((k, inner), obs)]
            if not inner:
                made += [((e.face, False), e) for e in self._observe_ends(t, k, inliers, pts, in_map, refined,
                                                                          robot)]
            for key, o in made:
                o = o if gnss_valid else replace(o, gnss=False)
                found.append(o)
                self.walls.setdefault(key, deque(maxlen=self.p.observations_per_wall)).append(o)
        if found:
            self._fit(anchor)
        return found

    def _visible_faces(self, robot: tuple, z: float) -> list:
        """(face index, inner) of the walls the robot can see from where it is: inside a building (under its
        roof), that building's inner faces; outside, the outer faces turned towards it. A wall whose line
        the robot is within the gate of (in its window: which side the robot is on is not clear) is left
        out, and does not decide inside or outside; the others still count (from a window, the room)."""
        standing = [k for k, f in enumerate(self.faces) if f.top > z and not f.end]
        side = {k: self._side(k, robot) for k in standing}
        clear = {k for k in standing if not (abs(side[k]) < min(self._gate(k, False), self.p.side_gate)
                                             and -0.5 < self._along(self.faces[k], np.array([robot]))[0]
                                             < self.faces[k].length + 0.5)}
        buildings = {self.faces[k].building for k in standing}
        outside = {self.faces[k].building for k in clear if side[k] > 0.0}
        inside = buildings - outside
        if inside:
            return [(k, True) for k in clear if self.faces[k].building in inside]
        return [(k, False) for k in clear if side[k] > 0.0]

    def _side(self, k: int, xy: tuple) -> float:
        """Signed distance of xy from face k's outer line (> 0 outside)."""
        f = self.faces[k]
        return f.normal[0] * xy[0] + f.normal[1] * xy[1] - f.offset

    @staticmethod
    def _along(f: Face, pts: np.ndarray) -> np.ndarray:
        ux, uy = (f.b[0] - f.a[0]) / f.length, (f.b[1] - f.a[1]) / f.length
        return (pts[:, 0] - f.a[0]) * ux + (pts[:, 1] - f.a[1]) * uy

    def _gate(self, k: int, inner: bool) -> float:
        """How far from a wall's predicted line its returns may lie: the prediction's std (3 sigma) + the
        tight gate, up to the wide one."""
        f, cov = self.faces[k], self.correction.cov
        j = np.array([f.normal[0], f.normal[1], 0.0, -1.0 if inner else 0.0])
        std = math.sqrt(max(float(j @ cov @ j), 0.0))
        wide = self.p.gate_unobserved if inner else self.p.gate_unobserved_outside
        return min(wide, self.p.gate + 3.0 * std)

    def _observe(self, t: float, k: int, inner: bool, pts: np.ndarray, in_map: np.ndarray,
                 refined: Anchor) -> Optional[WallObservation]:
        """The wall line in this scan's returns (arena frame pts, map frame in_map), or None."""
        p, f = self.p, self.faces[k]
        if not len(pts):
            return None
        line = f.offset - (self.correction.thickness if inner else 0.0)
        d = pts @ np.array(f.normal) - line
        along = self._along(f, pts)
        gate = self._gate(k, inner)
        # past a corner end (outside), as far as that end may be off: its returns are the wall's
        ext = [self._gate(self.ends[(k, i)], False) if not inner and (k, i) in self.ends else 0.3 for i in (0, 1)]
        on_wall = (along > -ext[0]) & (along < f.length + ext[1])
        looked = on_wall & (d > -gate) & (d < max(gate, p.look_beyond))
        if looked.sum() < p.min_points:
            return None
        outermost = self._outermost_surface(d[looked], along[looked])
        if outermost is None or outermost >= gate:
            return None                      # nothing there, or a surface beyond the wall's gate: not the wall
        sel = looked & (d > outermost - SURFACE_DEPTH)
        if sel.sum() < p.min_points:
            return None
        # robust line: start from the returns near a Theil-Sen line of offset against place along the wall
        # (a perpendicular interior wall meeting this one spreads its returns across the gate; the yaw
        # error tilts the wall's), then trimmed total least squares
        keep = np.abs(d[sel] - theil_sen(along[sel], d[sel])) < max(0.5 * p.gate, 0.1)
        idx = np.flatnonzero(sel)[keep]
        q = in_map[idx]
        for _ in range(3):
            if len(q) < p.min_points:
                return None
            centroid = q.mean(axis=0)
            direction, normal = np.linalg.svd(q - centroid, full_matrices=False)[2]
            res = (q - centroid) @ normal
            inl = np.abs(res) < 3.0 * max(1.4826 * float(np.median(np.abs(res))), 0.01)
            if inl.all():
                break
            q, idx = q[inl], idx[inl]
        else:
            if len(q) < p.min_points:
                return None
            centroid = q.mean(axis=0)
            res = (q - centroid) @ normal
        u = (q - centroid) @ direction
        span = float(u.max() - u.min())
        bins = np.unique(np.floor((u - u.min()) / COVERAGE_BIN)).size
        rms = float(np.sqrt(np.mean(res ** 2)))
        angle = float(wrap_half(math.atan2(direction[1], direction[0])))
        off_angle = float(wrap_half(angle + refined.theta - f.direction))
        if (span < p.min_span or bins < p.min_coverage * (span / COVERAGE_BIN + 1.0) or rms > p.max_line_rms
                or abs(off_angle) > p.max_line_angle):
            return None
        rms = max(rms, 0.005)
        return (WallObservation(t, k, inner, (float(centroid[0]), float(centroid[1])), angle, len(q),
                                rms / math.sqrt(len(q)), rms * math.sqrt(12.0 / len(q)) / max(span, 1e-3)), idx)

    def _observe_ends(self, t: float, k: int, inliers: np.ndarray, pts: np.ndarray, in_map: np.ndarray,
                      refined: Anchor, robot: tuple) -> list:
        """The corner ends of outer face k seen in this scan (arena frame pts, map frame in_map; `inliers`:
        the indices of its line's returns), as observations of their virtual faces. Rules: an end is where
        the line's returns stop within the end's gate of where the anchor predicts it, with returns in
        `end_coverage` of the last metre's stretches before it, none on the line for a metre past it (the
        wall goes on: not its end) and none nearer than the line in the bearings of that metre (something in
        front hides it: the returns stop at its shadow), within `end_max_range` of the robot. Placed half the
        last returns' spacing past the last one (the beam spacing at that range and slant), that much its
        std. Why: from outside, the facade gives its normal only; the GNSS error along it (0.5-1.8 m at the
        windows in the explore + GNSS-denied benchmark, 108-113) came in with the robot and was the largest
        SLAM error of every flight."""
        p, f = self.p, self.faces[k]
        out = []
        n = np.array(f.normal)
        u = np.array([f.b[0] - f.a[0], f.b[1] - f.a[1]]) / f.length
        along = self._along(f, pts)
        d = pts @ n - f.offset
        s_line, d_line = along[inliers], float(np.median(d[inliers]))
        for i in (0, 1):
            vk = self.ends.get((k, i))
            if vk is None:
                continue
            sign = 1.0 if i == 1 else -1.0                  # along the wall, outwards past this end
            s = sign * s_line                               # so that the end is the largest
            s_end_pred = sign * (f.length if i == 1 else 0.0)
            last = int(np.argmax(s))
            s_last = float(s[last])
            if abs(s_last - s_end_pred) > self._gate(vk, False):
                continue
            end_xy = np.array(f.a) + u * sign * s_last + n * d_line
            reach = math.hypot(end_xy[0] - robot[0], end_xy[1] - robot[1])
            if reach > p.end_max_range or reach + 1.0 > self.range_max:
                continue                                    # too far, or where the laser's reach ends
            tail = np.sort(s[s > s_last - 1.0])                # the line's returns of its last metre
            bins = np.unique(np.floor((s_last - tail) / COVERAGE_BIN)).size
            if bins < p.end_coverage * (1.0 / COVERAGE_BIN):
                continue
            sa = sign * along
            past = (sa > s_last + 0.1) & (sa < s_last + 1.0)
            if np.any(past & (np.abs(d - d_line) < 0.5)):
                continue                                    # the wall goes on past it
            if self._hidden(robot, pts, [np.array(f.a) + u * sign * (s_last + x) + n * d_line for x in (0.1, 1.0)]):
                continue
            gaps = np.diff(tail)
            half = min(0.5 * float(np.median(gaps[-3:])) if gaps.size else 0.1, 0.3)
            last_map = in_map[inliers[last]]
            u_map = transform(u[None, :], -refined.theta, 0.0, 0.0)[0]      # the wall's direction, map frame
            at = last_map + u_map * sign * half
            out.append(WallObservation(t, vk, False, (float(at[0]), float(at[1])), 0.0, 1,
                                       max(half, 0.03), math.inf))
        return out

    @staticmethod
    def _hidden(robot: tuple, pts: np.ndarray, segment: list) -> bool:
        """True when a return lies nearer to the robot than the segment (arena, two points) in the bearings
        that the segment covers: something in front of it."""
        r = np.asarray(robot[:2], dtype=float)
        b = [math.atan2(q[1] - r[1], q[0] - r[0]) for q in segment]
        lo, width = b[0], wrap_angle(b[1] - b[0])
        if width < 0:
            lo, width = b[1], -width
        rel = pts - r
        bearing = np.arctan2(rel[:, 1], rel[:, 0])
        within = ((bearing - lo) % (2 * math.pi)) <= width
        if not within.any():
            return False
        nearest_seg = min(float(np.hypot(*(q - r))) for q in segment)
        return bool(np.any(np.hypot(rel[within, 0], rel[within, 1]) < nearest_seg - 0.3))

    def _outermost_surface(self, d: np.ndarray, along: np.ndarray) -> Optional[float]:
        """The offset of the outermost surface parallel to a wall among returns at offsets d (> 0 outwards)
        and places `along` it: the outermost band 2 SURFACE_BIN deep holding `surface_points` returns
        spread over `surface_spread` m of its length. Rule: an outline wall is the building's outermost
        surface, from inside (its inner face: beyond it only what a window shows, further out) and from
        outside (its outer face: nothing stands between it and the robot but small things). So the caller
        takes the outermost surface within the gate and `look_beyond` m outwards, and none when it lies
        beyond the gate: an interior wall parallel to an outer wall is not taken for it when the outer
        wall is seen beyond it (through a doorway), and when the outer wall is only glimpsed the line
        found there fails the coverage checks. Narrow things (a window's reveal, a holder, a robot) do
        not make a surface."""
        p = self.p
        band = np.floor(d / SURFACE_BIN).astype(int)
        for b in np.unique(band)[::-1]:
            mine = (band == b) | (band == b - 1)
            if mine.sum() >= p.surface_points and np.ptp(along[mine]) >= p.surface_spread:
                return float(d[mine].max())
        return None

    # ---------------------------------------------------------------- the correction
    def _fit(self, anchor: Anchor) -> None:
        """Fit the correction on the kept observations against `anchor`: without GNSS, on those made
        without it alone when they observe both directions and the yaw (`indoor_takeover`), else on every
        one. Why: the crossing of a window or door is where hector_mapping's pose is likeliest to slip (the
        scan turns from the facade to the room); observations from before it, in the frame before the
        slip, held a re-entering UAV 0.15 m off for 40 s (mission seed 113, rtf 4) while the room's walls
        seen from inside said where it was."""
        rows = self._rows(anchor)
        if rows is None:
            return
        indoors = ~rows["gnss"]
        if self.p.indoor_takeover and not self.gnss_valid and indoors.any() and not indoors.all():
            corr = self._fit_rows(rows, indoors.copy(), quiet=True)
            if corr is not None and corr.observed == 2 and corr.yaw_observed:
                self._accept(corr)
                return
        corr = self._fit_rows(rows, np.ones(len(rows["key"]), dtype=bool))
        if corr is not None:
            self._accept(corr)

    def _accept(self, corr: Correction) -> None:
        if not self.p.thickness_min <= corr.thickness <= self.p.thickness_max:
            self.events.append(f"outline: fitted walls {corr.thickness:.2f} m thick, beyond "
                               f"{self.p.thickness_min}-{self.p.thickness_max} m: the observations disagree; "
                               f"rejected, keeping the previous correction")
            return
        shift = self._shift_at_pivot(corr)
        if shift > self.p.max_correction or abs(corr.transform.theta) > self.p.max_yaw_correction:
            self.events.append(f"outline: fitted correction {shift:.2f} m, {corr.transform.theta:+.3f} rad is "
                               f"beyond the bounds ({self.p.max_correction} m, {self.p.max_yaw_correction} rad): "
                               f"rejected, keeping the previous one")
            return
        self.correction = corr

    def _fit_rows(self, rows: dict, use: np.ndarray, quiet: bool = False) -> Optional[Correction]:
        """The correction fitted on the rows in `use`, or None. A wall that the fit of the others predicts
        well but misses by more than `max_wall_residual` is left out (the worst first, one at a time): a fit
        on all of them would spread its error over the others and the thickness. quiet: no log events."""
        self.dropped.clear()
        x = self._solve(rows, use)
        while True:
            # the fit of all walls spreads a wrong wall's error; while none is missed by half the limit
            # there is no wall to leave out (and the leave-one-out fits are not worth their CPU)
            keys = {k for k, u in zip(rows["key"], use) if u}
            if x is None or max(abs(self._wall_residual(rows, np.array([k == key for k in rows["key"]]), x)[0])
                                for key in keys) <= 0.5 * self.p.max_wall_residual:
                break
            worst = None
            for key in keys:
                mine = np.array([k == key for k in rows["key"]])
                others = self._solve(rows, use & ~mine)
                if others is None:
                    continue
                res, std = self._wall_residual(rows, mine, others)
                if std < self.p.max_std and abs(res) > self.p.max_wall_residual and (
                        worst is None or abs(res) > abs(worst[1])):
                    worst = (key, res)
            if worst is None:
                break
            self.dropped.add(worst[0])
            use &= np.array([k != worst[0] for k in rows["key"]])
            f = self.faces[worst[0][0]]
            if not quiet:
                self.events.append(f"outline: wall {f.name} ({'inner' if worst[0][1] else 'outer'} face) is "
                                   f"{worst[1]:+.2f} m off the fit of the others: left out")
            x = self._solve(rows, use)
        return None if x is None else self._correction(rows, use, *x)

    @staticmethod
    def _shift_at_pivot(corr: Correction) -> float:
        x, y, _ = corr.transform.apply(corr.pivot[0], corr.pivot[1], 0.0)
        return math.hypot(x - corr.pivot[0], y - corr.pivot[1])

    def _rows(self, anchor: Anchor) -> Optional[dict]:
        """The kept observations as arrays in the arena frame under `anchor`: wall key, face normal, outer
        offset, inner flag, centroid, line angle minus the wall's, weights (each wall counts as one
        observation however many scans saw it); the pivot (their weighted centre)."""
        p = self.p
        obs = [(key, o, len(q)) for key, q in self.walls.items() for o in q]
        if not obs:
            return None
        f = [self.faces[o.face] for _, o, _ in obs]
        c, s = math.cos(anchor.theta), math.sin(anchor.theta)
        m = np.array([o.centroid for _, o, _ in obs])
        g = np.column_stack((c * m[:, 0] - s * m[:, 1] + anchor.tx, s * m[:, 0] + c * m[:, 1] + anchor.ty))
        n_obs = np.array([n for _, _, n in obs], dtype=float)
        w_off = 1.0 / (n_obs * (np.array([o.sigma_offset for _, o, _ in obs]) ** 2 + p.wall_sigma ** 2))
        rows = {"key": [key for key, _, _ in obs], "normal": np.array([fk.normal for fk in f]),
                "offset": np.array([fk.offset for fk in f]),
                "inner": np.array([o.inner for _, o, _ in obs], dtype=float), "g": g,
                "gnss": np.array([o.gnss for _, o, _ in obs], dtype=bool),
                "angle": wrap_half(np.array([o.angle + anchor.theta - fk.direction for (_, o, _), fk in zip(obs, f)])),
                "w_off": w_off,
                "w_ang": 1.0 / (n_obs * (np.array([o.sigma_angle for _, o, _ in obs]) ** 2 + p.angle_sigma ** 2))}
        rows["pivot"] = (w_off[:, None] * g).sum(axis=0) / w_off.sum()
        return rows

    def _offset_residuals(self, rows: dict, x: np.ndarray) -> tuple:
        """Each row's offset residual under x = (dx, dy at the pivot, dyaw, thickness), and its Jacobian."""
        c, s = math.cos(x[2]), math.sin(x[2])
        rel = rows["g"] - rows["pivot"]
        moved = rows["pivot"] + np.column_stack((c * rel[:, 0] - s * rel[:, 1], s * rel[:, 0] + c * rel[:, 1])) + x[:2]
        n = rows["normal"]
        r = (n * moved).sum(axis=1) - rows["offset"] + rows["inner"] * x[3]
        drot = np.column_stack((-s * rel[:, 0] - c * rel[:, 1], c * rel[:, 0] - s * rel[:, 1]))
        jac = np.column_stack((n[:, 0], n[:, 1], (n * drot).sum(axis=1), rows["inner"]))
        return r, jac

    def _solve(self, rows: dict, use: np.ndarray) -> Optional[tuple]:
        """(x, covariance) by Gauss-Newton on the rows in `use` and the prior; None without rows."""
        if not use.any():
            return None
        p = self.p
        thickness, sigma = self.thickness_prior
        prior = np.array([0.0, 0.0, 0.0, thickness])
        prior_info = np.diag([p.prior_sigma ** -2] * 2 + [p.yaw_prior_sigma ** -2, sigma ** -2])
        w_off, w_ang = rows["w_off"] * use, rows["w_ang"] * use
        x = prior.copy()
        for _ in range(5):
            r, jac = self._offset_residuals(rows, x)
            ra = rows["angle"] + x[2]
            h = prior_info + (jac * w_off[:, None]).T @ jac
            h[2, 2] += w_ang.sum()
            b = prior_info @ (prior - x) - jac.T @ (w_off * r)
            b[2] -= (w_ang * ra).sum()
            step = np.linalg.solve(h, b)
            x = x + step
            if np.abs(step).max() < 1e-7:
                break
        return x, np.linalg.inv(h)

    def _wall_residual(self, rows: dict, mine: np.ndarray, fit: tuple) -> tuple:
        """A wall's mean offset residual under a fit without it, and the fit's std of that prediction."""
        x, cov = fit
        r, jac = self._offset_residuals(rows, x)
        w = rows["w_off"] * mine
        j = (jac * w[:, None]).sum(axis=0) / w.sum()
        return float((w * r).sum() / w.sum()), math.sqrt(max(float(j @ cov @ j), 0.0))

    def _correction(self, rows: dict, use: np.ndarray, x: np.ndarray, cov: np.ndarray) -> Correction:
        """The fitted x as a correction, each direction corrected only once observed. Rule: a direction not (or
        no longer) observed is not corrected; holding its last correction was tried (c3_floor_plan_b seed 101:
        an error along facade B, corrected from its corners, came back 0.6 m when their observations aged out
        a second before entering) and reverted: outdoors, fits 2.9 m off (hector sliding along a facade) were
        held into the tower, whole flights 2.8-3.6 m off and two UAVs crashed (realistic seed 103, rtf 4)."""
        p = self.p
        shift, dyaw = x[:2].copy(), float(x[2])
        vals, vecs = np.linalg.eigh(cov[:2, :2])
        observed = 0
        for val, v in zip(vals, vecs.T):
            if math.sqrt(max(val, 0.0)) > p.max_std:
                shift -= float(v @ shift) * v
            else:
                observed += 1
        yaw_observed = math.sqrt(cov[2, 2]) <= p.max_yaw_std
        if not yaw_observed:
            dyaw = 0.0
        pivot = rows["pivot"]
        c, s = math.cos(dyaw), math.sin(dyaw)
        t = pivot + shift - np.array([c * pivot[0] - s * pivot[1], s * pivot[0] + c * pivot[1]])
        walls = len({k for k, u in zip(rows["key"], use) if u})
        gnss = rows["gnss"][use]
        return Correction(Anchor(dyaw, float(t[0]), float(t[1])), float(x[3]), observed, yaw_observed, walls,
                          cov, (float(pivot[0]), float(pivot[1])), crossing=bool(gnss.any() and not gnss.all()))

    def pop_events(self) -> list:
        ev, self.events = self.events, []
        return ev


class CorrectionSmoother:
    """The correction actually applied: it follows the fitted one at a bounded rate, measured at the
    robot (so a newly observed direction does not make the pose a robot flies on jump), or at once while no
    one flies on it (`step(..., at_once=True)`: on GNSS the robots fly on the UAL's pose)."""

    def __init__(self, rate: float = 1.0, yaw_rate: float = 0.1):
        self.rate, self.yaw_rate = rate, yaw_rate       # m/s, rad/s
        self.applied = IDENTITY
        self.t: Optional[float] = None

    def reset(self) -> None:
        self.applied, self.t = IDENTITY, None

    def step(self, t: float, target: Anchor, at: tuple, at_once: bool = False) -> Anchor:
        """Move the applied correction towards target, measured at `at` (x, y arena), and return it;
        at_once: the whole way."""
        dt = 0.0 if self.t is None else max(t - self.t, 0.0)
        self.t = t
        if at_once:
            self.applied = target
            return target
        a = self.applied
        ax, ay, _ = a.apply(at[0], at[1], 0.0)
        bx, by, _ = target.apply(at[0], at[1], 0.0)
        dx, dy = bx - ax, by - ay
        dist = math.hypot(dx, dy)
        lim = self.rate * dt
        if dist > lim:
            dx, dy = dx * lim / dist, dy * lim / dist
        dth = wrap_angle(target.theta - a.theta)
        dth = max(-self.yaw_rate * dt, min(self.yaw_rate * dt, dth))
        theta = wrap_angle(a.theta + dth)
        c, s = math.cos(theta), math.sin(theta)
        # new(q) = R(theta) (q - at) + (applied(at) + step)
        px, py = ax + dx, ay + dy
        self.applied = Anchor(theta, px - (c * at[0] - s * at[1]), py - (s * at[0] + c * at[1]))
        return self.applied


__all__ = ["Face", "outline_faces", "transform", "RefineParams", "WallObservation",
           "Correction", "OutlineRefiner", "CorrectionSmoother", "IDENTITY", "wrap_half"]
