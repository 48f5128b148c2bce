"""Analytic RGB-D rendering of the axis-aligned world for a level camera (RealSense D435i model).

Why analytic: a 640 x 480 frame at 15 Hz must cost a few milliseconds in NumPy. The UAV model never rolls
or pitches, so the camera is level: a pixel column is a vertical half-plane, a column's horizontal ray meets
each box over a depth interval [Zin, Zout] (a 2D slab test over 640 columns x boxes), and within that column
a pixel row enters the box through its side (depth Zin), its top or its bottom face (depth from the face
height). Each visible box is painted into its own image rectangle only, nearest depth wins. Then fire holders
are drawn as discs in their image rectangles: holes (dark, with depth behind the wall: the container) and the
two decoy circles (dark, on the wall), and ground fires as red silk (or the grey blanket once covered).
Depth is z-depth (distance along the optical axis) in millimetres, 0 = no data (outside 0.2-10 m).
"""
from __future__ import annotations

import math

import numpy as np

from . import constants as C
from .fires import GROUND, FireSet

try:  # optional: only used for the final upsampling
    import cv2 as _cv2
    _cv2.setNumThreads(1)   # a 2-core machine shared by many nodes: no OpenCV worker threads
except ImportError:  # pragma: no cover - the project's venv has OpenCV
    _cv2 = None
from .world import World

SKY_BGR = (235, 206, 135)
GROUND_BGR = (120, 170, 200)      # sand
HOLE_BGR = (15, 15, 15)
DECOY_BGR = (30, 30, 30)
SILK_BGR = (20, 20, 210)
BLANKET_BGR = (90, 90, 90)
HOLE_DEPTH_BEHIND = 0.3            # m: the container behind the hole


class RGBDCamera:
    """Renders (bgr8 (H, W, 3) uint8, depth 16UC1 (H, W) uint16 mm) frames of a World."""

    def __init__(self, width: int = C.CAM_WIDTH, height: int = C.CAM_HEIGHT, fx: float = C.CAM_FX,
                 fy: float = C.CAM_FY, cx: float = C.CAM_CX, cy: float = C.CAM_CY, geo_scale: int = 2):
        self.w, self.h, self.fx, self.fy, self.cx, self.cy = width, height, fx, fy, cx, cy
        self.xu = (np.arange(width) - cx) / fx            # column -> right offset per metre of depth
        self.kv = (np.arange(height) - cy) / fy           # row -> downward offset per metre of depth
        self.offset = np.array(C.CAM_OFFSET)
        self.half_fov = math.atan(max(cx, width - cx) / fx)
        # the box geometry is painted on a grid `geo_scale` times coarser, then repeated up: edges of walls
        # and windows get 2-pixel steps, the discs (what the circle detector needs) stay at full resolution
        k = geo_scale if width % geo_scale == 0 and height % geo_scale == 0 else 1
        self.geo = _Grid(width // k, height // k, fx / k, fy / k, (cx - 0.5 * (k - 1)) / k, (cy - 0.5 * (k - 1)) / k)
        self.geo_scale = k

    def camera_info(self) -> dict:
        """Pinhole intrinsics (plumb_bob, no distortion) for sensor_msgs/CameraInfo."""
        return {"width": self.w, "height": self.h,
                "K": [self.fx, 0.0, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0],
                "P": [self.fx, 0.0, self.cx, 0.0, 0.0, self.fy, self.cy, 0.0, 0.0, 0.0, 1.0, 0.0]}

    def render(self, world: World, fires: FireSet, pos: np.ndarray, yaw: float) -> tuple[np.ndarray, np.ndarray]:
        """Colour (bgr8) and aligned depth (uint16 mm) seen by the camera of a robot at pos, heading yaw."""
        c, s = math.cos(yaw), math.sin(yaw)
        fwd, right = np.array([c, s]), np.array([s, -c])
        cam = pos + np.array([c * self.offset[0] - s * self.offset[1], s * self.offset[0] + c * self.offset[1],
                              self.offset[2]])
        cz = float(cam[2])
        g = self.geo
        depth = np.empty((g.h, g.w), dtype=np.float32)
        label = np.zeros((g.h, g.w), dtype=np.int32)      # 0 sky, 1 ground, 2 + 3*box + face
        # ground: level camera -> z-depth of the ground depends on the row only
        below = g.kv > 1e-6
        zg = np.where(below, cz / np.where(below, g.kv, 1.0), np.inf).astype(np.float32)
        depth[:] = zg[:, None]
        label[below, :] = 1
        # boxes: 2D slab test of the column rays (unnormalised: t is z-depth)
        far = C.CAM_DEPTH_MAX * 3.0
        sel = world.boxes_in_cone(cam, np.array([c, s, 0.0]), self.half_fov + 0.8, far)
        if len(sel):
            dirs = fwd[None, :] + g.xu[:, None] * right[None, :]          # (w, 2)
            zin, zout = _slab_intervals(cam[:2], dirs, world.bmin[sel, :2], world.bmax[sel, :2])
            fin = np.isfinite(zin) & (zout > 1e-3)
            zi_all = np.where(fin, np.maximum(zin, 1e-3), np.inf)
            first = zi_all.min(axis=0)
            order = np.argsort(first)
            order = order[np.isfinite(first[order])]        # boxes no column ray meets are dropped here
            if len(order):
                # column span and row span of every box at once (rows from its z range at entry and exit)
                f = fin[:, order]
                u0 = f.argmax(axis=0)
                u1 = g.w - f[::-1].argmax(axis=0)
                z0s, z1s = world.bmin[sel[order], 2], world.bmax[sel[order], 2]
                zi_o = np.where(f, zi_all[:, order], np.nan)
                zo_o = np.where(f, zout[:, order], np.nan)
                with np.errstate(invalid="ignore", divide="ignore"):
                    vs = np.stack([g.cy - g.fy * (z1s - cz) / zi_o, g.cy - g.fy * (z0s - cz) / zi_o,
                                   g.cy - g.fy * (z1s - cz) / zo_o, g.cy - g.fy * (z0s - cz) / zo_o])
                v0 = np.clip(np.floor(np.nanmin(vs, axis=(0, 1))), 0, g.h).astype(int)
                v1 = np.clip(np.ceil(np.nanmax(vs, axis=(0, 1))) + 1, 0, g.h).astype(int)
                for n, j in enumerate(order):               # front to back: occluded boxes are skipped cheaply
                    if v0[n] >= v1[n]:
                        continue
                    b = sel[j]
                    _paint_box(g, depth, label, zi_all[:, j], zout[:, j], z0s[n], z1s[n], cz, b,
                               int(u0[n]), int(u1[n]), int(v0[n]), int(v1[n]))
        # colour and millimetres on the coarse grid, then both up to full resolution in one copy each
        bgr = self._palette(world).take(label, axis=0, mode="wrap")
        dmm = _to_mm(depth)
        k = self.geo_scale
        if k > 1:
            dmm = _upsample(dmm, k)
            bgr = _upsample(bgr, k)
        # fire holders at full resolution (label of the coarse grid tells what surface is seen)
        if len(fires.fires):
            self._paint_wall_discs(dmm, bgr, fires, cam, fwd, right)
            self._paint_ground_discs(dmm, bgr, label, fires, cam, fwd, right)
        return bgr, dmm

    # ------------------------------------------------------------------ discs
    def _pixel_rect(self, pts: np.ndarray, cam: np.ndarray, fwd: np.ndarray, right: np.ndarray):
        """Image rectangle (v0, v1, u0, u1) covering world points pts (N, 3), or None if behind/outside."""
        rel = pts - cam
        zc = rel[:, :2] @ fwd
        if np.any(zc < C.CAM_DEPTH_MIN):
            return None
        u = self.cx + self.fx * (rel[:, :2] @ right) / zc
        v = self.cy - self.fy * rel[:, 2] / zc
        u0, u1 = int(max(0, math.floor(u.min()))), int(min(self.w, math.ceil(u.max()) + 1))
        v0, v1 = int(max(0, math.floor(v.min()))), int(min(self.h, math.ceil(v.max()) + 1))
        if u0 >= u1 or v0 >= v1:
            return None
        return v0, v1, u0, u1

    def _paint_wall_discs(self, depth, bgr, fires: FireSet, cam, fwd, right) -> None:
        """Holes and decoys: the wall is vertical, so the ray-plane depth depends on the column only."""
        span = C.DECOY_OFFSET + C.DECOY_RADIUS
        rel = fires.pos - cam
        ahead = rel[:, :2] @ fwd
        cand = ((fires.kind != GROUND) & (np.einsum("fk,fk->f", rel, fires.normal) < 0.0)
                & (ahead > C.CAM_DEPTH_MIN) & (ahead < C.CAM_DEPTH_MAX * 1.5)
                & (np.abs(rel[:, :2] @ right) < ahead * math.tan(self.half_fov) + span))
        for i in np.nonzero(cand)[0]:
            n, u = fires.normal[i], fires.u[i]
            # three circles side by side: the hole in the middle, a decoy on each side; each is drawn in its
            # own small image rectangle (a few thousand pixels) rather than one rectangle around all three
            for off, rad, colour, is_hole in ((0.0, C.HOLE_RADIUS, HOLE_BGR, True),
                                              (-C.DECOY_OFFSET, C.DECOY_RADIUS, DECOY_BGR, False),
                                              (C.DECOY_OFFSET, C.DECOY_RADIUS, DECOY_BGR, False)):
                ctr = fires.pos[i] + off * u
                self._disc_on_wall(depth, bgr, cam, fwd, right, ctr, n, u, rad, colour, is_hole)

    def _disc_on_wall(self, depth, bgr, cam, fwd, right, ctr, n, u, rad, colour, is_hole) -> None:
        """Paint one disc of a vertical wall where that wall is the visible surface (hole: 0.3 m deeper)."""
        corners = ctr + np.array([[a * rad * u[0], a * rad * u[1], b * rad] for a in (-1, 1) for b in (-1, 1)])
        rect = self._pixel_rect(corners, cam, fwd, right)
        if rect is None:
            return
        v0, v1, u0, u1 = rect
        dh = fwd[None, :] + self.xu[u0:u1, None] * right[None, :]          # (w, 2) column rays
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((ctr - cam) @ n) / (dh @ n[:2])                           # (w,) z-depth on the wall
        a = (cam[:2] + dh * t[:, None] - ctr[:2]) @ u[:2]                  # (w,) along the wall
        b = (cam[2] - ctr[2]) - self.kv[v0:v1, None] * t[None, :]        # (h, w) up the wall
        blk_d = depth[v0:v1, u0:u1]                                        # uint16 mm
        disc = ((a * a)[None, :] + b * b < rad * rad) & (
            np.abs(blk_d.astype(np.float32) - (1000.0 * t)[None, :]) < 150.0)
        bgr[v0:v1, u0:u1][disc] = colour
        if is_hole:
            blk_d[disc] = np.broadcast_to(_to_mm(t + HOLE_DEPTH_BEHIND)[None, :], disc.shape)[disc]

    def _paint_ground_discs(self, depth, bgr, label, fires: FireSet, cam, fwd, right) -> None:
        """Red silk (or the blanket) on the ground: the ground depth depends on the row only."""
        r = C.GROUND_PLATE_RADIUS * 1.5            # red silk larger than the plate
        if cam[2] <= 0.05:
            return
        for i in fires.ground_idx:
            f = fires.fires[i]
            if not f.active:
                continue
            ctr = fires.pos[i]
            corners = ctr + np.array([[a * r, b * r, 0.0] for a in (-1, 1) for b in (-1, 1)])
            rect = self._pixel_rect(corners, cam, fwd, right)
            if rect is None:
                continue
            v0, v1, u0, u1 = rect
            kv = self.kv[v0:v1]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = np.where(kv > 1e-6, cam[2] / kv, np.inf)                    # (h,)
            dh = fwd[None, :] + self.xu[u0:u1, None] * right[None, :]          # (w, 2)
            px = cam[0] - ctr[0] + t[:, None] * dh[None, :, 0]
            py = cam[1] - ctr[1] + t[:, None] * dh[None, :, 1]
            k = self.geo_scale
            ground = label[np.arange(v0, v1) // k][:, np.arange(u0, u1) // k] == 1   # ground is what is seen
            disc = (px * px + py * py < r * r) & ground
            bgr[v0:v1, u0:u1][disc] = BLANKET_BGR if f.covered else SILK_BGR
            depth[v0:v1, u0:u1][disc] = np.broadcast_to(_to_mm(t)[:, None], disc.shape)[disc]

    def _palette(self, world: World) -> np.ndarray:
        """BGR colour per label: sky, ground, then (side, top, bottom) shades of every box."""
        nb = len(world.bmin)
        if getattr(self, "_pal_n", -1) != nb:
            rgb = world.box_color.astype(np.float32)
            shades = np.stack([rgb * 0.85, rgb * 1.0, rgb * 0.6], axis=1).reshape(-1, 3)  # side, top, bottom
            pal = np.concatenate([np.array([SKY_BGR, GROUND_BGR], np.float32), shades[:, ::-1]])
            self._pal = pal.clip(0, 255).astype(np.uint8)
            self._pal_n = nb
        return self._pal


def _paint_box(g: "_Grid", depth, label, zin, zout, z0, z1, cz, b, u0, u1, v0, v1) -> None:
    """Paint box b into its image rectangle [v0, v1) x [u0, u1) of columns whose rays meet its footprint.

    zin is the entry z-depth per column (inf where missed; clamped to a small positive value when the
    camera is inside the footprint, e.g. under a slab, so the box is entered through its top or bottom).
    """
    zi, zo = zin[u0:u1], zout[u0:u1]
    valid = np.isfinite(zi)
    zi, zo = np.where(valid, zi, 1.0), np.where(valid, zo, 1.0)
    blk_d = depth[v0:v1, u0:u1]
    if blk_d.max() <= zi[valid].min():                 # everything here is already nearer: occluded
        return
    k = g.kv[v0:v1, None].astype(np.float32)        # (h, 1): height drop per metre of depth
    zi, zo = zi.astype(np.float32), zo.astype(np.float32)
    h_in = cz - k * zi[None, :]                        # ray height on entering the column interval
    side = (h_in >= z0) & (h_in <= z1)
    z = np.where(side, zi[None, :], np.float32(np.inf))
    face = np.zeros(h_in.shape, dtype=np.int32)
    with np.errstate(divide="ignore", invalid="ignore"):
        if cz > z1:                                    # top face seen from above
            zt = (cz - z1) / k
            top = (~side) & (h_in > z1) & (k > 0) & (zt <= zo[None, :])
            z = np.where(top, zt, z)
            face = np.where(top, 1, face)
        if cz < z0:                                    # bottom face seen from below
            zb = (cz - z0) / k
            bot = (~side) & (h_in < z0) & (k < 0) & (zb <= zo[None, :])
            z = np.where(bot, zb, z)
            face = np.where(bot, 2, face)
    if not valid.all():
        z[:, ~valid] = np.inf
    closer = z < blk_d
    blk_d[closer] = z[closer]
    label[v0:v1, u0:u1][closer] = 2 + 3 * b + face[closer]


def _to_mm(z: np.ndarray) -> np.ndarray:
    """z-depth in metres -> uint16 millimetres, 0 outside the sensor's 0.2-10 m range."""
    z = np.asarray(z, dtype=np.float32)
    ok = (z >= C.CAM_DEPTH_MIN) & (z <= C.CAM_DEPTH_MAX)
    return np.where(ok, z * 1000.0, 0.0).astype(np.uint16)


def _upsample(img: np.ndarray, k: int) -> np.ndarray:
    """Nearest-neighbour k x k upsampling (OpenCV when available: several times faster than NumPy here)."""
    if _cv2 is not None:
        return _cv2.resize(img, (img.shape[1] * k, img.shape[0] * k), interpolation=_cv2.INTER_NEAREST)
    return np.repeat(np.repeat(img, k, axis=0), k, axis=1)


class _Grid:
    """Pixel grid of a pinhole camera: column and row offsets per metre of depth."""

    def __init__(self, w: int, h: int, fx: float, fy: float, cx: float, cy: float):
        self.w, self.h, self.fx, self.fy, self.cx, self.cy = w, h, fx, fy, cx, cy
        self.xu = (np.arange(w) - cx) / fx
        self.kv = (np.arange(h) - cy) / fy


def _slab_intervals(o: np.ndarray, d: np.ndarray, bmin: np.ndarray, bmax: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(W, B) entry and exit parameters of 2D rays against rectangles; inf where missed or behind."""
    tnear = tfar = None
    for k in range(2):
        dk = d[:, k]
        inv = 1.0 / np.where(np.abs(dk) < 1e-12, 1e-12, dk)
        a = np.multiply.outer(inv, bmin[:, k] - o[k])
        b = np.multiply.outer(inv, bmax[:, k] - o[k])
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        if tnear is None:
            tnear, tfar = lo, hi
        else:
            tnear, tfar = np.maximum(tnear, lo), np.minimum(tfar, hi)
    miss = (tnear > tfar) | (tfar <= 0.0)
    return np.where(miss, np.inf, tnear), np.where(miss, np.inf, tfar)
