"""TeraRanger Evo Thermal 33 model: 32 x 32 apparent temperatures by ray casting 1024 pixel rays.

Temperature model: what a pixel ray hits (sun-heated wall, interior wall, ground, sky), then fire holders on
walls (a flame ring around a hole with a heater in its centre, cooling as water arrives; an inactive holder is
cold) and ground plates (hot, or lukewarm under a blanket), then the contrast fades with distance and
Gaussian noise is added. Why ray casting of every pixel: the image is tiny (1024 rays) and culling to the
boxes within range keeps it around a millisecond.
"""
from __future__ import annotations

import math

import numpy as np

from . import constants as C
from .fires import GROUND, FireSet
from .world import GROUND as HIT_GROUND, NO_HIT, World

FORWARD, DOWNWARD = 1, 2   # mbzirc_comm_objs/ThermalImage camera_direction


FACE_BEHIND = 0.05   # m behind a holder's face a ray's hit still counts as on it (a wall is thicker)

def pixel_dirs(direction: int, size: int = C.THERMAL_SIZE, fov: float = C.THERMAL_FOV) -> np.ndarray:
    """(size*size, 3) unit pixel rays in base_link, row-major, row 0 = top of the image.

    FORWARD looks along +x (image up = +z, image right = -y); DOWNWARD looks along -z with the image top
    towards the UAV front (+x) and image right = -y.
    """
    f = 0.5 * size / math.tan(0.5 * fov)
    r, c = np.meshgrid(np.arange(size) + 0.5 - 0.5 * size, np.arange(size) + 0.5 - 0.5 * size, indexing="ij")
    a, b = -r.ravel() / f, -c.ravel() / f   # a: up in the image, b: left in the image
    if direction == DOWNWARD:
        d = np.stack([a, b, -np.ones_like(a)], axis=1)
    else:
        d = np.stack([np.ones_like(a), b, a], axis=1)
    return d / np.linalg.norm(d, axis=1, keepdims=True)


class ThermalCamera:
    """Renders temperature frames for one mounting direction (pixel rays precomputed once)."""

    def __init__(self, direction: int = FORWARD, noise_std: float = C.THERMAL_NOISE_STD):
        self.direction = direction
        self.noise_std = noise_std
        self.body_dirs = pixel_dirs(direction)
        self.axis = np.array([0.0, 0.0, -1.0]) if direction == DOWNWARD else np.array([1.0, 0.0, 0.0])
        self.side_normals = _side_normals(self.body_dirs)
        self.offset = np.array(C.THERMAL_OFFSET_DOWNWARD if direction == DOWNWARD else C.THERMAL_OFFSET_FORWARD)

    def render(self, world: World, fires: FireSet, pos: np.ndarray, yaw: float,
               rng: np.random.Generator | None = None) -> np.ndarray:
        """(32, 32) float64 temperatures in deg C seen from a robot at pos with heading yaw."""
        app = self.render_clean(world, fires, pos, yaw)
        if rng is not None and self.noise_std > 0.0:
            app = app + rng.normal(0.0, self.noise_std, app.shape)
        return app

    def render_clean(self, world: World, fires: FireSet, pos: np.ndarray, yaw: float) -> np.ndarray:
        """The noise-free frame (what a cache may keep while nothing moves)."""
        c, s = math.cos(yaw), math.sin(yaw)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        origin = pos + rot @ self.offset
        dirs = self.body_dirs @ rot.T
        near = world.boxes_in_frustum(origin, self.side_normals @ rot.T, C.THERMAL_MAX_RANGE)
        t, idx = world.raycast(origin, dirs, C.THERMAL_MAX_RANGE, boxes=near)
        temp = np.where(idx >= 0, world.box_temp[np.maximum(idx, 0)], C.SKY_TEMP)
        temp = np.where(idx == HIT_GROUND, C.GROUND_TEMP, temp)
        hit = np.isfinite(t)
        if hit.any() and len(fires.fires):
            temp = self._fires(fires, origin, dirs, t, idx, temp, hit)
        dist = np.where(hit, t, 0.0)
        contrast = 1.0 / (1.0 + (dist / C.THERMAL_ATTEN_DIST) ** 2)
        app = np.where(hit, C.AMBIENT_TEMP + (temp - C.AMBIENT_TEMP) * contrast, temp)
        return app.reshape(C.THERMAL_SIZE, C.THERMAL_SIZE)

    @staticmethod
    def _fires(fires: FireSet, origin: np.ndarray, dirs: np.ndarray, t: np.ndarray, idx: np.ndarray,
               temp: np.ndarray, hit: np.ndarray) -> np.ndarray:
        # only holders within range and in front of the camera
        rel_f = fires.pos - origin
        dist_f = np.linalg.norm(rel_f, axis=1)
        fsel = np.nonzero((dist_f < C.THERMAL_MAX_RANGE + 1.0)
                          & ((np.einsum("fk,fk->f", rel_f, fires.normal) < 0.0) | (dist_f < 1.0)))[0]
        if len(fsel) == 0:
            return temp
        rows = np.nonzero(hit)[0]
        p = origin + dirs[rows] * t[rows, None]                 # (H, 3) hit points
        cf = fires.pos[fsel]
        # squared distances hit point <-> holder as one matrix product (cheap), to keep only nearby pixels
        d2 = np.einsum("hk,hk->h", p, p)[:, None] - 2.0 * (p @ cf.T) + np.einsum("fk,fk->f", cf, cf)[None, :]
        close = (d2 < (max(C.FLAME_RING_RADIUS, C.GROUND_PLATE_RADIUS) + 0.3) ** 2).any(axis=1)
        rows, p = rows[close], p[close]
        if len(rows) == 0:
            return temp
        heat = fires.heat()[fsel]
        rel = p[:, None, :] - fires.pos[None, fsel, :]           # (H, F, 3)
        dn = np.einsum("hfk,fk->hf", rel, fires.normal[fsel])
        radial = np.linalg.norm(rel - dn[..., None] * fires.normal[None, fsel, :], axis=2)
        is_ground = fires.kind[fsel] == GROUND
        active = np.array([fires.fires[i].active for i in fsel])
        covered = np.array([fires.fires[i].covered for i in fsel])
        out = temp[rows].copy()
        base = out[:, None]
        # on the holder's own face (its wall's front): a wall's back face is as near to the holder as the wall is
        # thick (0.2 m) and showed the fire through it (realistic seed 107 at rtf 4: in1_e seen from behind its
        # interior wall within 1 m, watered from there three times, never put out)
        on_surface = (dn > -FACE_BEHIND) & (dn < 0.25)
        # wall holders: ring of flames and the heater in the hole; inactive ones are cold
        wall = on_surface & ~is_ground[None, :] & (radial < C.FLAME_RING_RADIUS)
        in_hole = radial < C.HOLE_RADIUS
        hot = np.where(in_hole, C.HEATER_TEMP, C.FLAME_TEMP)
        wall_t = np.where(active[None, :], base + (hot - base) * heat[None, :], C.INACTIVE_HOLDER_TEMP)
        # ground plates (only where the ray hit the ground)
        plate = (on_surface & is_ground[None, :] & (radial < C.GROUND_PLATE_RADIUS)
                 & (idx[rows] == HIT_GROUND)[:, None] & active[None, :])
        plate_t = np.where(covered[None, :], C.BLANKET_TEMP, C.HEATER_TEMP)
        cand = np.where(wall, wall_t, np.where(plate, plate_t, -np.inf))
        best = cand.max(axis=1)
        sel = np.isfinite(best)
        out[sel] = best[sel]
        temp = temp.copy()
        temp[rows] = out
        return temp


def _side_normals(dirs: np.ndarray) -> np.ndarray:
    """Inward normals of the 4 side planes of the pyramid spanned by the pixel rays (slightly widened)."""
    n = int(round(math.sqrt(len(dirs))))
    g = dirs.reshape(n, n, 3)
    corners = [g[0, 0], g[0, -1], g[-1, -1], g[-1, 0]]
    axis = dirs.mean(axis=0)
    out = []
    for a, b in zip(corners, corners[1:] + corners[:1]):
        nrm = np.cross(a, b)
        if nrm @ axis < 0:
            nrm = -nrm
        nrm /= np.linalg.norm(nrm)
        out.append(nrm - 0.02 * axis)      # widen by about a degree: pixel rays are centres, not edges
    return np.array(out)


def to_rgb(temps: np.ndarray) -> np.ndarray:
    """Colour-map a temperature frame on a relative scale (min..max of the frame), like the sensor's rgb_image."""
    lo, hi = float(temps.min()), float(temps.max())
    x = (temps - lo) / max(hi - lo, 1e-6)
    rgb = np.stack([np.clip(3.0 * x, 0, 1), np.clip(3.0 * x - 1.0, 0, 1), np.clip(3.0 * x - 2.0, 0, 1)], axis=-1)
    return (rgb * 255.0).astype(np.uint8)


__all__ = ["ThermalCamera", "FORWARD", "DOWNWARD", "pixel_dirs", "to_rgb", "NO_HIT"]
