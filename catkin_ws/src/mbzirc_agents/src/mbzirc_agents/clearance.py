"""Clearance guard: no motion command takes a flying UAV closer than `min_clearance` to the surface below,
whatever its GNSS height says.

Why: the UAL flies to set-points in the frame of its GNSS fix, whose vertical error wanders by decimetres
(standard GNSS, ual_sim README "Uncertainty"). A set-point 0.75 m up (facade holder A_4) then puts the
UAV on the ground when the fix reads 0.75 m high (seen: "hit the ground" at A_4 under realistic
uncertainty). The downward altimeter measures the true height above the surface below; the difference
between the GNSS height above the arena plan's surface and the measured height is the vertical GNSS
error `e` (GNSS z = true z + e). A set-point z is flown at true height z - e, so the guard keeps
z >= surface + clearance + e.

Rules:
- a reading's surface is the one of the arena plan below the UAV (ground, a roof, a storey's floor) that
  best explains it (closest to the last estimate of e): the candidates are metres apart, e decimetres;
  a reading that fits none (|e| > max_gnss_error), or that moves a fresh estimate by more than max_step
  while the reading jumped more than the GNSS height, is something the plan does not know (a window sill,
  a robot below): not believed, and after max_age of such readings the fallback applies until the
  readings make sense again; when the GNSS height jumped instead (a re-fix), the new error holds at once;
- set-points: z >= surface at the target + min_clearance + `hysteresis` + e; the caller re-sends a
  held set-point when that bound has risen by half the hysteresis (e wanders while the UAV holds);
- velocities: the vertical command never lets the height (the GNSS height now, corrected by e, above the
  last reading's surface) fall below min_clearance + hysteresis within `horizon` s (it climbs back when
  below);
- no fresh valid altimeter reading (stale, NaN, no return): e is unknown; the bounds use the GNSS height
  with `fallback_margin` more clearance (and the caller warns, throttled);
- passing an opening (`hold` .. `release`): readings are not believed (the altimeter sees the sill, or the
  wall's top, which the plan does not have); the estimate of the hold's start stays fresh for at most
  `hold_max_age`, then the fallback applies until the release; a stale estimate is not held. Why: a reading after a gap is taken without the jump test (a re-fix is
  believed at once), so a UAV held 1.5 s over a floor-1 window's sill (1.5 m above the storey's floor
  in the plan) took the sill for that floor, believed its fix 1.5 m low and climbed into the lintel.
- while a hold lasts, the UAV's own vertical velocity (the autopilot's, `on_velocity`: inertial, it does not
  drift with the GNSS error) is integrated from the true height at the hold's start (its GNSS height less
  the estimate then): the true height in the opening is that plus the climb since (`true_z`), and e is the
  GNSS height less it, so the estimate follows the GNSS error's wander instead of freezing, and stays fresh
  up to `tracked_hold_max_age` (15 s) while velocities keep coming (no velocity for `max_age`: the tracking ends,
  the held estimate's own `hold_max_age` applies). Why: the error wanders 0.3-0.5 m within 4 s; a frozen
  estimate let UAVs that stalled in a window follow that wander into its lintel or sill (realistic seeds
  101, 106: 0.5-0.8 m off the middle they had centred on after 5-10 s in the wall) and went stale after 8 s.
Pure: no ROS, no clock of its own (times are passed in), tested in test_clearance.py.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple


@dataclass(frozen=True)
class ClearanceConfig:
    """Numbers of the guard (the first three are agent params, README "Params")."""
    min_clearance: float = 0.5      # m of true height above the surface below, at least
    fallback_margin: float = 1.0    # m more when the altimeter gives nothing usable (GNSS height only)
    max_age: float = 1.5            # s: an older altimeter reading is stale (e moves ~0.1 m in that time)
    hysteresis: float = 0.2         # m: set-points aim this much above the clearance (see the rules; with
    #                                 0.1 the noise of the estimate let 0.2 % of a hold dip to 0.41 m, bench)
    horizontal_margin: float = 1.0  # m: a roof this close (xy) may be under the UAV (GNSS horizontal error)
    max_gnss_error: float = 3.0     # m: a reading implying a larger vertical error is not believed
    max_step: float = 0.5           # m: nor one moving a fresh estimate by more (a sill, a robot below)
    filter_tau: float = 0.3         # s: smoothing of e (noise of the fix and of the altimeter)
    horizon: float = 1.0            # s: a velocity may close the height to the bound in this time, not less
    hold_max_age: float = 8.0       # s: an estimate held through an opening (e drifts ~0.2 m in that time)
    tracked_hold_max_age: float = 15.0  # s: a hold tracked by the vertical velocity (an autopilot's velocity
    #                                     bias of ~0.02 m/s integrates to 0.3 m in that time; a crossing takes 2-5 s)


def surfaces_at(x: float, y: float, footprints: Sequence[Sequence[float]], floor_heights: Sequence[float],
                ground_z: float, roof_margin: float, floor_margin: float = 0.0) -> list:
    """Heights of the surfaces the arena plan may put under (x, y): the ground, the roof of every building
    whose footprint grown by roof_margin holds (x, y), and the storeys' floors (those below its roof) of
    every building whose footprint grown by floor_margin holds it."""
    out = [float(ground_z)]
    for b in footprints:
        x0, y0, x1, y1, top = (float(v) for v in b[:5])
        if x0 - roof_margin <= x <= x1 + roof_margin and y0 - roof_margin <= y <= y1 + roof_margin:
            out.append(top)
        if x0 - floor_margin <= x <= x1 + floor_margin and y0 - floor_margin <= y <= y1 + floor_margin:
            out.extend(float(f) for f in floor_heights if ground_z < f < top)
    return sorted(set(out))


class ClearanceGuard:
    """The vertical GNSS error estimated from the altimeter, and the bounds on set-points and velocities.

    Not thread-safe by itself: the agent calls it under its own lock."""

    def __init__(self, cfg: ClearanceConfig, footprints: Sequence[Sequence[float]],
                 floor_heights: Sequence[float], ground_z: float = 0.0) -> None:
        self.cfg = cfg
        self.footprints = [tuple(b) for b in footprints]
        self.floor_heights = tuple(floor_heights)
        self.ground_z = float(ground_z)
        self.error: Optional[float] = None      # e, m (GNSS z - true z), smoothed
        self.surface: Optional[float] = None    # the plan's surface under the last valid reading, m
        self._last = (math.nan, math.nan)       # (height read, GNSS z) of the last valid reading
        self.valid_time = -math.inf             # stamp of the last valid reading
        self.holding = False                    # passing an opening: readings ignored until the release
        self.held_until = -math.inf             # the held estimate counts as fresh until then
        self.hold_start = -math.inf
        self.held_true_z: Optional[float] = None  # true z at the hold's start, while the velocity tracks it
        self.climb = 0.0                        # m climbed since then (integrated vertical velocity)
        self.velocity_time = -math.inf          # stamp of the last vertical velocity integrated
        self.last_problem = 'no altimeter reading yet'

    # ---- input -------------------------------------------------------------------------------------------
    def surfaces(self, x: float, y: float, floors_near: bool = False) -> list:
        """The plan's surfaces that may be under (x, y) (roofs within the horizontal margin; storey floors
        inside the footprint, or within the margin too with floors_near: what a reading may have seen in a
        window, whose GNSS position may be outside)."""
        m = self.cfg.horizontal_margin
        return surfaces_at(x, y, self.footprints, self.floor_heights, self.ground_z, m, m if floors_near else 0.0)

    def on_reading(self, reading: float, stamp: float, gnss_xyz: Sequence[float]) -> None:
        """One altimeter reading (REP 117: -inf too close, +inf no return, NaN invalid) taken at `stamp`
        when the GNSS position was gnss_xyz."""
        r = float(reading)
        if self.holding:
            self.last_problem = 'readings ignored while passing an opening (its sill is not in the plan)'
            return
        if math.isnan(r):
            self.last_problem = 'invalid (NaN) reading'
            return
        if r == math.inf:
            self.last_problem = 'no return (beyond the maximum range)'
            return
        if not all(math.isfinite(v) for v in gnss_xyz[:3]):
            self.last_problem = 'no valid GNSS position at the reading'
            return
        h = max(0.0, r)                          # -inf: closer than the minimum range
        x, y, z = (float(v) for v in gnss_xyz[:3])
        prior = self.error if self.error is not None else 0.0
        e, surface = min(((z - h - s, s) for s in self.surfaces(x, y, floors_near=True)),
                         key=lambda c: abs(c[0] - prior))
        if abs(e) > self.cfg.max_gnss_error:
            self.last_problem = (f'reading {h:.2f} m fits no surface of the plan (would mean a GNSS height '
                                 f'error of {e:+.1f} m): something below the UAV?')
            return
        fresh = self.error is not None and stamp - self.valid_time <= self.cfg.max_age
        if fresh and abs(e - self.error) > self.cfg.max_step:
            dh, dz = h - self._last[0], z - self._last[1]
            if abs(dh) > abs(dz):       # the reading jumped, not the fix: something the plan does not know
                self.last_problem = (f'reading {h:.2f} m jumps the GNSS height error estimate by '
                                     f'{e - self.error:+.1f} m: something below the UAV (a sill, a robot)?')
                return
            fresh = False               # the fix jumped (a re-fix), the reading did not: the new error at once
        if not fresh:
            self.error = e                        # first reading, or fresh after a gap: no smoothing
        else:
            dt = max(0.0, stamp - self.valid_time)
            a = 1.0 - math.exp(-dt / self.cfg.filter_tau) if self.cfg.filter_tau > 0 else 1.0
            self.error += a * (e - self.error)
        self.surface, self.valid_time, self._last = surface, stamp, (h, z)
        self.last_problem = 'none since (no reading arrived)'

    def on_velocity(self, vz: float, stamp: float, gnss_z: float) -> None:
        """The UAV's vertical velocity (m/s, the autopilot's) at `stamp`, when its GNSS height was gnss_z: while a
        tracked hold lasts, integrated into the climb since its start, and e follows (see the rules). A gap
        of more than max_age between two ends the tracking (the climb meanwhile is unknown); a NaN is
        ignored."""
        if self.held_true_z is None or not (math.isfinite(vz) and math.isfinite(gnss_z)):
            return
        dt = stamp - self.velocity_time
        if dt > self.cfg.max_age:
            self.held_true_z = None                     # not tracked any more: the held estimate's own age rule
            self.held_until = min(self.held_until, self.hold_start + self.cfg.hold_max_age)
            self.last_problem = f'no vertical velocity for {dt:.1f} s while passing an opening'
            return
        if dt > 0.0:
            self.climb += float(vz) * dt
            self.velocity_time = float(stamp)
            self.error = float(gnss_z) - (self.held_true_z + self.climb)

    # ---- state ---------------------------------------------------------------------------------------------
    def fresh(self, now: float) -> bool:
        """True when the last valid reading is at most max_age old, or the estimate is held (a tracked hold:
        while its velocities keep coming)."""
        if now - self.valid_time <= self.cfg.max_age:
            return True
        if self.error is None or now > self.held_until:
            return False
        return self.held_true_z is None or now - self.velocity_time <= self.cfg.max_age

    def tracking(self, now: float) -> bool:
        """True while a hold's true height is tracked by the vertical velocity (fresh, see on_velocity)."""
        return self.held_true_z is not None and now <= self.held_until and now - self.velocity_time <= self.cfg.max_age

    def true_z(self, gnss_z: float, now: float) -> Optional[float]:
        """The UAV's true height: while tracking, the hold's start height plus the climb since (no GNSS in it:
        not even its noise); else the GNSS height less a fresh e; None without either."""
        if self.tracking(now):
            return self.held_true_z + self.climb
        if self.fresh(now) and self.error is not None:
            return float(gnss_z) - self.error
        return None

    def hold(self, now: float, gnss_z: Optional[float] = None) -> bool:
        """Ignore readings until release(); the estimate as it is now counts as fresh for at most
        hold_max_age, or, given the GNSS height now (gnss_z), is tracked by the vertical velocity from the
        true height now for at most tracked_hold_max_age. False when it is not fresh (nothing to hold: the
        fallback applies meanwhile)."""
        self.holding = True
        if self.error is None or now - self.valid_time > self.cfg.max_age:
            return False
        self.hold_start = now
        self.held_until = now + self.cfg.hold_max_age
        if gnss_z is not None and math.isfinite(gnss_z):
            self.held_true_z, self.climb, self.velocity_time = float(gnss_z) - self.error, 0.0, now
            self.held_until = now + self.cfg.tracked_hold_max_age
        return True

    def release(self) -> None:
        """End a hold: readings count again (after a hold longer than max_age the next one is taken as it is,
        as after any gap: past the opening the altimeter sees a surface of the plan)."""
        self.holding, self.held_until, self.held_true_z = False, -math.inf, None

    def problem(self, now: float) -> str:
        """Why the guard is on its fallback now ('' when it is not)."""
        if self.fresh(now):
            return ''
        age = now - self.valid_time
        since = 'never' if math.isinf(age) else f'for {age:.1f} s'
        return f'no valid altimeter reading {since} (last: {self.last_problem})'

    def _error_and_clearance(self, now: float) -> Tuple[float, float]:
        """(e to correct with, clearance to keep): the altimeter's when fresh, else 0 and the fallback."""
        if self.fresh(now) and self.error is not None:
            return self.error, self.cfg.min_clearance + self.cfg.hysteresis
        return 0.0, self.cfg.min_clearance + self.cfg.fallback_margin

    def surface_below(self, x: float, y: float, true_z: float, clearance: float) -> float:
        """The highest plan surface under (x, y) that a UAV at true height true_z must keep `clearance`
        above (a surface higher than true_z + clearance is a wall beside it, not under it)."""
        below = [s for s in self.surfaces(x, y) if s <= true_z + clearance]
        return max(below) if below else self.ground_z

    # ---- bounds --------------------------------------------------------------------------------------------
    def min_set_point_z(self, x: float, y: float, z: float, now: float) -> float:
        """Lowest set-point z (GNSS frame) the UAL may be sent to at (x, y) when asked for z."""
        e, clearance = self._error_and_clearance(now)
        s = self.surface_below(x, y, z - e, clearance)
        return s + clearance + e

    def safe_set_point_z(self, x: float, y: float, z: float, now: float) -> float:
        """z, raised to the bound when below it."""
        return max(float(z), self.min_set_point_z(x, y, z, now))

    def height_now(self, gnss_xyz: Sequence[float], now: float) -> Tuple[float, float]:
        """(height above the surface below, clearance to keep): with a fresh estimate the GNSS height now,
        corrected by e, above the surface of the last reading (the reading itself may be a few tenths of a
        second old); else the GNSS height above the plan's surface, with the fallback clearance."""
        e, clearance = self._error_and_clearance(now)
        x, y, z = (float(v) for v in gnss_xyz[:3])
        if self.fresh(now) and self.surface is not None:
            return z - e - self.surface, clearance
        return z - self.surface_below(x, y, z, clearance), clearance

    def safe_vz(self, vz: float, gnss_xyz: Sequence[float], now: float) -> float:
        """The vertical velocity, limited so that the height does not fall below the clearance within
        `horizon` s; a positive (climbing) command when already below it."""
        h, clearance = self.height_now(gnss_xyz, now)
        return max(float(vz), (clearance - h) / self.cfg.horizon)


__all__ = ['ClearanceConfig', 'ClearanceGuard', 'surfaces_at']
