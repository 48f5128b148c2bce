"""Whether a watered fire still stands out of its wall, read on the raw thermal image (not the detector's answer).

Why not the fire detector's CheckFire answer: the detector reports a fire only while it stands ~min_contrast
(30 degC) above the frame's median, a test made to reject sun-heated walls, not to say "out". A fire whose heat
fades as water arrives falls under it well before it is out (ideal missions: indoor fires judged out at 85 % and
98.5 % watered, after the detector stopped reporting them).

The measure (FireContrast): when the detector sees the fire, its frame is locked: the fire's core is the pixels
that rise at least CORE_SHARE of the way from the frame's cool part (its LOW_PERCENTILE) to its hottest pixel,
its surroundings every pixel SURROUND_GAP px or more from the core. Each later frame's contrast is the mean of
the core minus the wall's level under it: a plane fitted to the surroundings, pixels off it by more than 3
robust deviations dropped (the fire's cooler parts: a heater in a hole, a flame's rim). The difference removes
the camera's offset and the wall's own level and slope (a sun-heated wall reads 35-55 degC, warmer on its
sunny side), and the means over the core and the surroundings average the pixel noise down, so that a fire is
cold when that contrast falls to the noise level (~out_contrast), not when it falls under a detection
threshold. The aim is frozen while the detector no longer sees the fire (tasks/indoor.py), so the fire stays
on the locked pixels.
"""
from __future__ import annotations

import math
import threading
from typing import Callable, NamedTuple, Optional

import numpy as np

FRAME_SIZE = 32            # TeraRanger Evo Thermal 33: 32 x 32 temperatures, row-major
LOW_PERCENTILE = 10.0      # the frame's cool part: the wall the fire is on (a fire rarely fills 90 % of it)
CORE_SHARE = 0.5           # core: the pixels at least half way from the wall to the hottest pixel
SURROUND_GAP = 2           # surroundings: the pixels at least this far from the core (its blurred edge)
MIN_CORE = 2               # pixels: fewer cannot be told from a glitching pixel
MIN_SURROUND = 16          # pixels: fewer give no reliable wall level
LOCK_MIN_RISE = 2.0        # x ~out_contrast a frame's fire must stand over its wall to be locked: clearly warmer
                           # than the cold verdict's level (a top-up's fire at 95 % reads 5-10 degC at 1.5 m)
MAX_AGE = 1.5              # s: with no frame this recent the camera says nothing (no evidence)
RING_TRIES = 3             # warm areas that ring no hole left out, at most, when looking for one that does
MAX_HOLE_SHARE = 0.3       # of the frame at most, the cooler area a ringed core encloses: a holder's hole seen
                           # from 1 m or more (wider: a window's opening framed by a warm wall, seen from afar)
RING_STEP_SHARE = 0.25     # a ring's hole reads at least this share of the ring's rise over the frame's cool
                           # part below the ring pixels around it: cooler for real, not by the camera's noise,
RING_MIN_STEP = 0.5        # and at least this share of the rise asked of the ring itself (min_rise)


def frame_of(data) -> Optional[np.ndarray]:
    """The 32 x 32 frame of a raw_temp_array's data (non-finite pixels NaN), None when it has another size or
    no finite value."""
    arr = np.asarray(data, dtype=np.float64)
    if arr.ndim != 1 or arr.size != FRAME_SIZE * FRAME_SIZE:
        return None
    arr = np.where(np.isfinite(arr), arr, np.nan)
    if np.isnan(arr).all():
        return None
    return arr.reshape(FRAME_SIZE, FRAME_SIZE)


def _dilate(mask: np.ndarray, gap: int) -> np.ndarray:
    """mask grown by gap pixels (a square neighbourhood)."""
    h, w = mask.shape
    padded = np.pad(mask, gap)
    out = np.zeros_like(mask)
    for dy in range(2 * gap + 1):
        for dx in range(2 * gap + 1):
            out |= padded[dy:dy + h, dx:dx + w]
    return out


def lock_masks(frame: np.ndarray, min_rise: float) -> Optional[tuple]:
    """(core, surroundings) boolean masks of the fire in frame, None when nothing rises min_rise above the
    wall (its hottest pixel, and the core's contrast: a sun-heated wall's slope is no fire) or either part is
    too small to measure."""
    valid = np.isfinite(frame)
    low = float(np.nanpercentile(frame, LOW_PERCENTILE))
    rise = float(np.nanmax(frame)) - low
    if not rise >= min_rise:
        return None
    core = np.where(valid, frame, -np.inf) >= low + CORE_SHARE * rise
    surround = valid & ~_dilate(core, SURROUND_GAP)
    if core.sum() < MIN_CORE or surround.sum() < MIN_SURROUND:
        return None
    if not contrast(frame, (core, surround)) >= min_rise:
        return None
    return core, surround


_ROWS, _COLS = np.mgrid[0:FRAME_SIZE, 0:FRAME_SIZE].astype(np.float64)
_PLANE = np.stack([np.ones(FRAME_SIZE * FRAME_SIZE), _ROWS.ravel(), _COLS.ravel()], axis=1)


def wall_plane(flat: np.ndarray, idx: np.ndarray, rounds: int, warm_only: bool) -> np.ndarray:
    """Coefficients (_PLANE's columns) of the plane fitted to the pixels idx of a flattened frame, refitted up
    to `rounds` times without the pixels farther than 3 robust deviations from it (warm_only: only those
    above it, the warm areas standing out of a wall), while MIN_SURROUND pixels remain."""
    for _ in range(rounds):
        coef = np.linalg.lstsq(_PLANE[idx], flat[idx], rcond=None)[0]
        resid = flat[idx] - _PLANE[idx] @ coef
        spread = 1.4826 * float(np.median(np.abs(resid))) + 1e-6
        keep = (resid if warm_only else np.abs(resid)) <= 3.0 * spread
        if keep.all() or keep.sum() < MIN_SURROUND:
            break
        idx = idx[keep]
    return coef


def contrast(frame: np.ndarray, masks: tuple) -> float:
    """deg C the locked core reads above its surroundings in frame (NaN when either part has too few valid
    pixels): the core's mean less the wall's level under it, a plane fitted to the surroundings (a sun-heated
    wall is warmer on its sunny side, and the surroundings need not lie evenly around the fire); pixels
    farther than 3 robust deviations from the first fit (a glitching pixel, a warm object) are dropped."""
    core, surround = masks
    flat = frame.ravel()
    hot = flat[core.ravel()]
    hot = hot[np.isfinite(hot)]
    idx = np.flatnonzero(surround.ravel() & np.isfinite(flat))
    if not hot.size or idx.size < MIN_SURROUND:
        return math.nan
    coef = wall_plane(flat, idx, rounds=2, warm_only=False)
    wall = _PLANE[core.ravel()] @ coef
    return float(hot.mean() - wall[np.isfinite(flat[core.ravel()])].mean())


def _grow4(mask: np.ndarray) -> np.ndarray:
    """mask grown by one pixel up, down, left and right."""
    out = mask.copy()
    out[1:, :] |= mask[:-1, :]
    out[:-1, :] |= mask[1:, :]
    out[:, 1:] |= mask[:, :-1]
    out[:, :-1] |= mask[:, 1:]
    return out


def enclosed(core: np.ndarray) -> np.ndarray:
    """The pixels outside core that core encloses: not 4-connected to the frame's border through pixels
    outside it (a fire holder's hole inside its ring of flames)."""
    free = ~core
    outside = np.zeros_like(core)
    for edge in ((0, slice(None)), (-1, slice(None)), (slice(None), 0), (slice(None), -1)):
        outside[edge] = free[edge]
    while True:
        grown = _grow4(outside) & free
        if (grown == outside).all():
            return free & ~outside
        outside = grown


class Spot(NamedTuple):
    """A fire's centre in a frame (pixel 0's centre = 0), as `warm_spot` finds it."""
    column: float
    row: float
    whole: bool     # the centre is the fire's (not a core cut by the frame's edge around no enclosed area)
    ringed: bool    # the warm core encloses a cooler area: a holder's hole in its ring of flames


class FrameSpot(NamedTuple):
    """A Spot in FireContrast's latest frame: when it was taken and how far it stands over its wall."""
    column: float
    row: float
    time: float
    whole: bool
    contrast: float   # deg C over its wall
    ringed: bool


def warm_spot(frame: np.ndarray, min_rise: float) -> Optional[Spot]:
    """The fire's centre in frame (Spot: column, row, whole, ringed), pixel 0's centre = 0; None when nothing stands
    min_rise over its wall (`lock_masks`). The centre is the centroid of the warm core with the cooler area it
    encloses (a holder's hole ringed by flames); when the core reaches the frame's edge, the centroid of that
    enclosed area alone. whole: that centre is the fire's (False: a core cut by the frame's edge around no
    enclosed area, whose centroid lies short of the fire's centre, towards the image's).
    Why: at the watering distance a holder's ring of flames is as wide as the camera's view, and the centroid
    of the part of it inside the frame stays near the image centre whatever the aim (ual_sim's realistic
    world, a UAV at 1.5 m, its watering distance: a fire 5.8 deg off the heading read 3.6 deg off; at 1.2 m,
    where the GNSS fix's wander takes it, 0.0 deg, and at 1.0 m 3 deg the wrong way), while the hole it rings
    is whole in the frame and its centre is the fire's (there: within 0.3 deg)."""
    masks = lock_masks(frame, min_rise)
    return None if masks is None else spot_of(masks[0], frame, min_rise)


def ringed_spot(frame: np.ndarray, min_rise: float) -> Optional[tuple]:
    """(Spot, masks) of a warm area standing min_rise over its wall that rings a cooler hole (a holder's ring
    of flames), looked for under warmer areas that ring none: each such core (with its blurred edge) is left
    out and the rest of the frame looked at again, RING_TRIES times at most; None without one.
    Why: a fire nearly put out stands a few degC over its wall, and a sun-heated outer wall in the same view
    stands 5-25 degC over the interior one (ual_sim's realistic profile, closed loop top-ups of fires at 97 %,
    bench_indoor_pour.py --progress 0.97: the wall's part of the view was the frame's warm core, the ring 1.3 m
    ahead of the UAV was never looked for, and a whole tank went onto the wall)."""
    frame = np.array(frame, dtype=np.float64)
    for _ in range(RING_TRIES):
        masks = lock_masks(frame, min_rise)
        if masks is None:
            return None
        spot = spot_of(masks[0], frame, min_rise)
        if spot.ringed:
            return spot, masks
        frame[_dilate(masks[0], SURROUND_GAP)] = np.nan
    return None


def largest_component(mask: np.ndarray) -> np.ndarray:
    """The largest 4-connected area of mask (empty when mask is)."""
    best = np.zeros_like(mask)
    left = mask.copy()
    while left.any():
        area = np.zeros_like(mask)
        area[np.unravel_index(int(np.argmax(left)), mask.shape)] = True
        while True:
            grown = _grow4(area) & left
            if (grown == area).all():
                break
            area = grown
        left &= ~area
        if area.sum() > best.sum():
            best = area
    return best


def ring_hole(core: np.ndarray, inside: np.ndarray, frame: Optional[np.ndarray] = None,
              min_rise: float = 0.0) -> np.ndarray:
    """The hole a warm core rings, from the area it encloses (`inside`: `enclosed(core)`): its largest
    4-connected part, at least 3 pixels across (a pixel of it whose four neighbours are in it too), and, given the
    frame, only when that part reads cooler than the core pixels around it by RING_STEP_SHARE of their rise
    over the frame's cool part (LOW_PERCENTILE) and by RING_MIN_STEP x min_rise (the rise asked of the ring);
    else empty. Why: a holder's hole is one area, tens of pixels from the watering distance, cooler than its
    flames by far more than the camera's noise (a fire at 97 %: 2 degC over its wall inside a ring 6 degC over
    it), while the noise dips single pixels and thin lines of them. With the cold sky of a window in the view, a
    whole wall stands as the frame's warm core and its noise pixels under the core's threshold are enclosed by
    it: ual_sim's renderer beside in1_w, a look towards facade B's window (looked at for realistic seed 117,
    whose misses had another cause: the look-around's pose, tasks/indoor.py `_looks`); closed loop pours
    (bench_indoor_pour.py) seeds 7, 8, 11 at in1_w / in2_w, the fire out: such a "ring" beside the watering
    pose kept it from being judged out."""
    hole = largest_component(inside)
    if not (hole[1:-1, 1:-1] & hole[:-2, 1:-1] & hole[2:, 1:-1] & hole[1:-1, :-2] & hole[1:-1, 2:]).any():
        return np.zeros_like(hole)
    if frame is None:
        return hole
    around = _dilate(hole, 1) & core & np.isfinite(frame)
    inside = hole & np.isfinite(frame)
    if not around.any() or not inside.any():
        return np.zeros_like(hole)
    ring, low = float(frame[around].mean()), float(np.nanpercentile(frame, LOW_PERCENTILE))
    if ring - float(frame[inside].mean()) >= max(RING_MIN_STEP * min_rise, RING_STEP_SHARE * (ring - low)):
        return hole
    return np.zeros_like(hole)


def spot_of(core: np.ndarray, frame: Optional[np.ndarray] = None, min_rise: float = 0.0) -> Spot:
    """The fire's centre for its warm core (`warm_spot`'s rule); `frame`, when given, tells a hole from noise
    (`ring_hole`, the core asked to stand min_rise over its wall)."""
    inside = enclosed(core)
    hole = ring_hole(core, inside, frame, min_rise)
    clipped = core[0, :].any() or core[-1, :].any() or core[:, 0].any() or core[:, -1].any()
    ringed = bool(hole.any() and hole.sum() <= MAX_HOLE_SHARE * hole.size)
    rows, cols = np.nonzero(hole if clipped and ringed else core | inside)
    return Spot(float(cols.mean()), float(rows.mean()), bool(ringed or not clipped), ringed)


def box_mean(frame: np.ndarray) -> np.ndarray:
    """frame averaged over each pixel's 3 x 3 neighbourhood (NaN pixels left out; the border's smaller ones)."""
    valid = np.isfinite(frame)
    padded = np.pad(np.where(valid, frame, 0.0), 1)
    count = np.pad(valid.astype(np.float64), 1)
    h, w = frame.shape
    total, n = np.zeros((h, w)), np.zeros((h, w))
    for dy in range(3):
        for dx in range(3):
            total += padded[dy:dy + h, dx:dx + w]
            n += count[dy:dy + h, dx:dx + w]
    with np.errstate(invalid='ignore', divide='ignore'):
        return np.where(n > 0, total / np.maximum(n, 1.0), np.nan)


def warm_area_contrast(frame: np.ndarray, min_rise: float) -> float:
    """deg C the frame's own warm area stands over its wall (`lock_masks` with min_rise on the 3 x 3 mean of
    the frame less the wall's plane: a sun-heated wall's slope across the frame is no warm area), 0 when none
    stands min_rise over it.
    Why the mean: on a cold wall the hottest few pixels of the camera's noise alone stand out of the rest
    (realistic cameras: 0.3-1.0 degC per pixel; at 1.0, 12 % of frames of a bare wall had such an area 2 degC
    over it, and a quenched fire 'showed hot again'); a fire is an area several pixels wide, which the mean
    keeps while it divides the noise by 3."""
    smooth = box_mean(frame)
    flat = smooth.ravel()
    idx = np.flatnonzero(np.isfinite(flat))
    if idx.size < MIN_SURROUND:
        return 0.0
    coef = wall_plane(flat, idx, rounds=3, warm_only=True)   # the wall's plane, the warm pixels dropped
    level = (flat - _PLANE @ coef).reshape(frame.shape)      # deg C over the wall's plane
    masks = lock_masks(level, min_rise)
    return 0.0 if masks is None else contrast(level, masks)


def pixel_bearing(column: float, fov_deg: float) -> float:
    """rad off the optical axis, positive to the left (a counter-clockwise turn), of a pixel column of the
    32-px-wide image (the detector's placement rule: fire_detector geometry.forward_fire_position); of a pixel
    row, rad above the axis (the image is square: its rows span the same field of view)."""
    focal = (FRAME_SIZE / 2.0) / math.tan(math.radians(fov_deg) / 2.0)
    return math.atan2(-(column - (FRAME_SIZE - 1) / 2.0), focal)


class FireContrast:
    """Raw thermal frames in (`on_frame`, at most one every `period` s is processed), the locked fire's
    contrast out (`answer`): True while it stands more than `out_contrast` above its wall, False at the noise
    level, None without a lock or a recent frame (no evidence either way)."""

    def __init__(self, now: Callable[[], float], out_contrast: float, period: float) -> None:
        self.now = now
        self.out_contrast, self.period = out_contrast, period
        self.lock = threading.Lock()
        self.frame: Optional[np.ndarray] = None
        self.previous: Optional[np.ndarray] = None   # the frame measured before it
        self.frame_time = -math.inf
        self.masks: Optional[tuple] = None
        self.locked_contrast = math.nan          # the contrast of the locked frame (the fire seen hot)
        self.contrasts: list = []                # of the frames measured since the last answer
        self.last = math.nan                     # the last answer's contrast (for the log)
        self.bad = 0                             # malformed frames seen (the task logs them)
        self.was_locked = False                  # a fire was locked since the last clear (`unlock` keeps it)
        self.warm: list = []                     # once a fire was locked: each frame's own warm area's contrast
                                                 # to its wall since the last answer (0: none out_contrast over it)

    def clear(self) -> None:
        with self.lock:
            self.masks, self.contrasts, self.frame, self.warm = None, [], None, []
            self.locked_contrast = self.last = math.nan
            self.was_locked = False

    def unlock(self) -> None:
        """Drop the locked pixels (the camera turned: they no longer hold the fire), keeping in mind that a fire
        was locked: frames from now on answer without a lock (`answer`), and `lock_on_latest(relock=True)` locks
        it again however faint it has become."""
        with self.lock:
            self.masks, self.contrasts, self.warm = None, [], []

    def on_frame(self, data) -> None:
        """A raw_temp_array's data (1024 deg C); processed when `period` s passed since the last one."""
        now = self.now()
        if now - self.frame_time < self.period:
            return
        frame = frame_of(data)
        with self.lock:
            if frame is None:
                self.bad += 1
                return
            self.previous, self.frame, self.frame_time = self.frame, frame, now
            if self.masks is not None:
                c = contrast(frame, self.masks)
                if math.isfinite(c):
                    self.contrasts.append(c)
            if self.was_locked:
                self.warm.append(warm_area_contrast(frame, self.out_contrast))

    def lock_on_latest(self, steady: bool = False, relock: bool = False) -> bool:
        """Lock the fire on the latest frame (called while the detector sees it); False when that frame has
        no fire that can be measured (the previous lock stays). steady (no detector to confirm it): the frame
        before must show the same warm area as warm (not a frame taken while the robot turned or moved).
        relock (a fire locked before, unlocked by a turn of the aim): any area standing out_contrast over its
        wall is locked, not only one standing LOCK_MIN_RISE x that (a first lock's evidence of a fire)."""
        with self.lock:
            if self.frame is None or self.now() - self.frame_time > MAX_AGE:
                return False
            min_rise = (1.0 if relock else LOCK_MIN_RISE) * self.out_contrast
            masks = lock_masks(self.frame, min_rise)
            if masks is None:
                return False
            if steady and (self.previous is None or not contrast(self.previous, masks) >= min_rise):
                return False
            self.masks, self.contrasts, self.warm = masks, [], []
            self.locked_contrast = contrast(self.frame, masks)
            self.was_locked = True
            return True

    def warm_spot(self, min_rise: float = LOCK_MIN_RISE, ringed: bool = False) -> Optional[FrameSpot]:
        """The fire's centre in the latest recent frame (module `warm_spot`, its warm core standing min_rise x
        ~out_contrast over its wall; ringed: only a core that rings a hole, `ringed_spot`), None without one."""
        with self.lock:
            if self.frame is None or self.now() - self.frame_time > MAX_AGE:
                return None
            if ringed:
                found = ringed_spot(self.frame, min_rise * self.out_contrast)
                spot, masks = found if found is not None else (None, None)
            else:
                masks = lock_masks(self.frame, min_rise * self.out_contrast)
                spot = None if masks is None else spot_of(masks[0], self.frame, min_rise * self.out_contrast)
            if spot is None:
                return None
            return FrameSpot(spot.column, spot.row, self.frame_time, spot.whole, contrast(self.frame, masks),
                             spot.ringed)

    @property
    def locked(self) -> bool:
        return self.masks is not None

    def fresh(self) -> bool:
        return self.now() - self.frame_time <= MAX_AGE

    def answer(self) -> Optional[bool]:
        """Hot (True) or cold (False) by the contrast of the latest frame since the last answer (each answer
        a new frame; the latest, as the fire changes under the water); None without a lock, a recent frame or
        a frame since, and when the locked core reads more than ~out_contrast under its wall (no fire is
        colder than its wall: the camera no longer looks at the locked area, seen when a robot backed off a
        wall: -21 degC). Cold needs the frame's own warm area (`lock_masks` on it) to stand no more than
        ~out_contrast over its wall too: locked pixels that read cold while a warm area shows elsewhere in the
        frame say hot (the fire moved in the image). Unlocked after a turn (`unlock`): cold when the latest
        frame since shows no such warm area, else None until the fire is locked again.
        Why (ual_sim's realistic profile, closed loop test_indoor_closed_loop.py): a lock dropped by a turn of
        the aim was taken again only on an area LOCK_MIN_RISE x out_contrast over its wall, so a fire put out
        after the turn never read cold ('tank ran dry before 6 cold answers (0 so far)' on fires put out by
        their first tank); and gusts push a UAV +-0.2-0.4 m sideways, which moves a fire at 1.5 m by 7-14 px
        in the image off its locked pixels: a fire at 98.4 % that still stood 3 degC over its wall read
        0.2-0.9 degC on them and was judged out."""
        with self.lock:
            values, self.contrasts = self.contrasts, []
            warm, self.warm = self.warm, []
            if self.now() - self.frame_time > MAX_AGE:
                return None
            if self.masks is None:
                if warm and warm[-1] <= self.out_contrast:
                    self.last = float(warm[-1])      # unlocked after a turn: nothing out_contrast over its wall
                    return False
                return None
            if not values:
                return None
            self.last = float(values[-1])
            if self.last < -self.out_contrast:
                return None
            if self.last <= self.out_contrast and warm and warm[-1] > self.out_contrast:
                self.last = float(warm[-1])          # the locked pixels cold, a warm area elsewhere in view
            return self.last > self.out_contrast
