"""The trial's uncertainty: what the real arena did not tell the robots, chosen per trial (`~uncertainty`).

Profiles live in the `uncertainty:` section of the world file; `ideal` is empty (every model off, the
simulator behaves exactly as without this module and draws no extra random numbers), `realistic` holds
the numbers of the ual_sim README ("Uncertainty", with where each comes from). Three kinds of models:

- GNSS error of every robot's reported pose: a first-order Gauss-Markov bias per robot and axis plus white
  noise. The robot's controller closes its loop on the reported pose, so a commanded waypoint is reached in
  the *believed* frame: the true position ends up offset by minus the bias (Simulation shifts the true
  set-point as the bias wanders). Collisions, water and the score use the truth.
- per-seed physical unknowns: water a fire needs, the jet's spot size and drop, sun-heated wall
  temperatures (the sun-facing side hotter), each thermal camera's noise and offset.
- laser range noise and dropouts (NaN and inf beams).

Why a separate random generator: `ideal` must reproduce today's trials bit for bit, so the uncertainty
never draws from the simulation's own generator.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Optional, Sequence

import numpy as np

PROFILES = ("ideal", "realistic")


class UncertaintyError(ValueError):
    """A malformed uncertainty section or an unknown profile; the message names the entry."""


def _num(section: Mapping, key: str, where: str, default: float) -> float:
    v = section.get(key, default)
    try:
        v = float(v)
    except (TypeError, ValueError) as e:
        raise UncertaintyError(f"{where}.{key}: must be a number, got {v!r}") from e
    if not math.isfinite(v) or v < 0.0 and not key.startswith(("offset", "drop")):
        raise UncertaintyError(f"{where}.{key}: must be a finite number >= 0, got {v!r}")
    return v


def _range(section: Mapping, key: str, where: str, default: Sequence[float]) -> tuple[float, float]:
    v = section.get(key, default)
    try:
        lo, hi = (float(x) for x in v)
    except (TypeError, ValueError) as e:
        raise UncertaintyError(f"{where}.{key}: must be [low, high], got {v!r}") from e
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        raise UncertaintyError(f"{where}.{key}: must be finite with low <= high, got {v!r}")
    return lo, hi


# ---------------------------------------------------------------------------------------------- GNSS
@dataclass(frozen=True)
class GnssConfig:
    """Standard (non-RTK) GNSS position error: per-axis Gauss-Markov bias std (m), its correlation time (s),
    and white noise std (m) added to every reported pose.

    `denied_indoors`: inside a building's footprint below its roof there is no fix; the reported position
    then dead-reckons from where the last fix put it (velocity-aided, as an autopilot with optical flow
    does): its error grows by a per-axis velocity bias (Gauss-Markov, std `indoor_vel_bias_std` m/s,
    correlation time `indoor_vel_bias_tau` s) plus a scale error (std `indoor_scale_std`, drawn per
    outage) times the true horizontal velocity. Height keeps the error it had (barometer). The defaults of
    the three drift numbers are the README's ("No GNSS indoors"); a world file may override them."""
    bias_xy_std: float = 0.0
    bias_z_std: float = 0.0
    tau: float = 30.0
    white_xy_std: float = 0.0
    white_z_std: float = 0.0
    denied_indoors: bool = False
    indoor_vel_bias_std: float = 0.02
    indoor_vel_bias_tau: float = 60.0
    indoor_scale_std: float = 0.02
    vel_white_std: float = 0.0
    vel_bias_std: float = 0.0
    vel_bias_tau: float = 20.0

    @property
    def enabled(self) -> bool:
        return self.denied_indoors or max(self.bias_xy_std, self.bias_z_std, self.white_xy_std,
                                          self.white_z_std) > 0.0

    @property
    def velocity_enabled(self) -> bool:
        return max(self.vel_white_std, self.vel_bias_std) > 0.0


class GaussMarkov:
    """First-order Gauss-Markov (Ornstein-Uhlenbeck) process per axis: stationary std `std`, correlation
    time `tau`. Exact discretisation: x' = a x + sqrt(1 - a^2) std w, a = exp(-dt / tau); it starts from its
    stationary distribution (a receiver that has been on for a while)."""

    def __init__(self, std: np.ndarray, tau: float, rng: np.random.Generator):
        self.std = np.asarray(std, dtype=float)
        self.tau = float(tau)
        self.rng = rng
        self.value = self.std * rng.standard_normal(self.std.shape)

    def step(self, dt: float) -> np.ndarray:
        a = math.exp(-dt / self.tau) if self.tau > 0 else 0.0
        self.value = a * self.value + math.sqrt(max(0.0, 1.0 - a * a)) * self.std * self.rng.standard_normal(
            self.std.shape)
        return self.value


class GnssError:
    """The position error of one robot's reported pose: outdoors the GNSS bias (slowly wandering) and the
    white noise of each fix; indoors without GNSS (`denied_indoors`) a smooth dead-reckoned error that
    starts from the last fix's bias (no jump on entering) and grows. Back outside the fix returns with the
    bias as it wandered meanwhile (the receiver's error never stopped): the reported pose jumps by the
    dead-reckoned drift, as an autopilot's estimate does when GNSS is re-acquired."""

    def __init__(self, cfg: GnssConfig, rng: np.random.Generator):
        self.cfg = cfg
        self.rng = rng
        self.bias = GaussMarkov(np.array([cfg.bias_xy_std, cfg.bias_xy_std, cfg.bias_z_std]), cfg.tau, rng)
        self.white_std = np.array([cfg.white_xy_std, cfg.white_xy_std, cfg.white_z_std])
        self.error = self.bias.value.copy()     # smooth part of the reported error (what a controller follows)
        self.denied = False                    # no fix now (indoors with denied_indoors)
        self._vel_bias: Optional[GaussMarkov] = None
        self._scale = np.zeros(2)

    def step(self, dt: float, indoors: bool = False, vel: Optional[np.ndarray] = None) -> np.ndarray:
        """Advance by dt (`indoors`: the robot is inside a building now; `vel`: its true velocity); returns
        the change of the smooth error (the shift of the true set-point is minus that)."""
        before = self.error.copy()
        self.bias.step(dt)
        if indoors and self.cfg.denied_indoors:
            if not self.denied:      # the fix is lost: this outage's dead-reckoning errors
                self.denied = True
                s = self.cfg.indoor_vel_bias_std
                self._vel_bias = GaussMarkov(np.array([s, s, 0.0]), self.cfg.indoor_vel_bias_tau, self.rng)
                self._scale = self.cfg.indoor_scale_std * self.rng.standard_normal(2)
            else:
                self._vel_bias.step(dt)
            rate = self._vel_bias.value.copy()
            if vel is not None:
                rate[:2] += self._scale * np.asarray(vel, dtype=float)[:2]
            self.error = self.error + rate * dt
        else:
            self.denied = False
            self.error = self.bias.value.copy()
        return self.error - before

    def fix(self) -> np.ndarray:
        """Error of one reported position (x, y, z): bias + white noise, or the dead-reckoned error."""
        if self.denied:
            return self.error.copy()
        return self.error + self.white_std * self.rng.standard_normal(3)


class VelocityError:
    """The error of one robot's reported velocity (`ual/velocity`, `ual/odom`'s twist): the autopilot's
    GNSS/inertial velocity estimate, per axis a Gauss-Markov bias (std `vel_bias_std`, correlation time
    `vel_bias_tau`: the accelerometers' residual bias) plus white noise (`vel_white_std`: the receiver's
    Doppler velocity). Why a model at all: a robot that integrates its velocity (e.g. to hold a height
    through a window without its altimeter) must meet the drift a real estimate has, not the truth."""

    def __init__(self, cfg: GnssConfig, rng: np.random.Generator):
        self.rng = rng
        self.white_std = float(cfg.vel_white_std)
        self.bias = GaussMarkov(np.full(3, float(cfg.vel_bias_std)), cfg.vel_bias_tau, rng)

    def step(self, dt: float) -> None:
        self.bias.step(dt)

    def reading(self) -> np.ndarray:
        """Error of one reported velocity (vx, vy, vz) in m/s."""
        return self.bias.value + self.white_std * self.rng.standard_normal(3)


def building_volumes(bmin: np.ndarray, bmax: np.ndarray, buildings: Sequence[str]) -> np.ndarray:
    """(K, 5) rows [x0, y0, x1, y1, roof_z] of every building (boxes tagged `building:`): its footprint is
    the horizontal extent of its outline (outer walls and roofs), its roof the top of its widest flat box
    (the top of its highest box if it has none), so that a roof structure does not raise the roof."""
    out = []
    tags = np.asarray(list(buildings), dtype=object)
    for name in sorted({b for b in buildings if b}):
        sel = np.nonzero(tags == name)[0]
        ext = bmax[sel] - bmin[sel]
        flat = np.argmin(ext, axis=1) == 2
        area = ext[:, 0] * ext[:, 1]
        roof = bmax[sel[np.argmax(np.where(flat, area, -1.0))], 2] if flat.any() else bmax[sel, 2].max()
        out.append([bmin[sel, 0].min(), bmin[sel, 1].min(), bmax[sel, 0].max(), bmax[sel, 1].max(), roof])
    return np.array(out, dtype=float).reshape(-1, 5)


def inside_building(p: Sequence[float], volumes: np.ndarray) -> bool:
    """True when p (x, y, z) is within a building's footprint and below its roof (no GNSS there)."""
    x, y, z = float(p[0]), float(p[1]), float(p[2])
    v = volumes
    return bool(np.any((v[:, 0] < x) & (x < v[:, 2]) & (v[:, 1] < y) & (y < v[:, 3]) & (z < v[:, 4])))


# ---------------------------------------------------------------------------------------------- laser
@dataclass(frozen=True)
class LaserConfig:
    """Range noise std = max(range_std_min, range_std_frac * range); dropouts: a beam reads NaN (no valid
    return) or inf (no echo) with these probabilities."""
    range_std_frac: float = 0.0
    range_std_min: float = 0.0
    nan_rate: float = 0.0
    inf_rate: float = 0.0

    @property
    def enabled(self) -> bool:
        return max(self.range_std_frac, self.range_std_min, self.nan_rate, self.inf_rate) > 0.0


def corrupt_scan(ranges: np.ndarray, cfg: LaserConfig, rng: np.random.Generator,
                 range_min: float, range_max: float) -> np.ndarray:
    """A noisy copy of a clean scan: Gaussian range noise on finite beams (kept within [range_min,
    range_max]), then NaN and inf dropouts."""
    out = np.array(ranges, dtype=float, copy=True)
    fin = np.isfinite(out)
    std = np.maximum(cfg.range_std_min, cfg.range_std_frac * np.where(fin, out, 0.0))
    out[fin] = np.clip(out[fin] + std[fin] * rng.standard_normal(int(fin.sum())), range_min, range_max)
    u = rng.random(out.shape)
    out[u < cfg.nan_rate] = np.nan
    out[(u >= cfg.nan_rate) & (u < cfg.nan_rate + cfg.inf_rate)] = np.inf
    return out


# ---------------------------------------------------------------------------------------------- physics
@dataclass(frozen=True)
class PhysicsConfig:
    """Ranges the per-seed unknowns are drawn from (uniform); None = that model is off."""
    fire_water_factor: Optional[tuple] = None     # x the nominal litres a fire needs, per fire
    jet_spot_factor: Optional[tuple] = None       # x the spot growth per metre, per trial
    jet_drop_per_m2: Optional[tuple] = None       # m the spot lands below the axis per m^2 flown, per trial
    wall_base_temp: Optional[tuple] = None        # deg C of the shaded sun-heated surfaces, per trial
    wall_sun_gain: float = 0.0                    # deg C added on a surface facing the sun squarely
    wall_temp_limits: tuple = (35.0, 55.0)        # deg C: every sun-heated surface stays within
    sun_azimuth_deg: tuple = (110.0, 250.0)       # from arena +y (north) towards +x (east)
    sun_elevation_deg: tuple = (30.0, 55.0)
    thermal_noise_std: Optional[tuple] = None     # deg C per camera
    thermal_offset: Optional[tuple] = None        # deg C per camera (calibration offset)


@dataclass
class Unknowns:
    """What one seed drew (the referee may log it; robots never read it)."""
    water_factor: np.ndarray                      # (F,) per fire of the FireSet
    jet_spot_factor: float = 1.0
    jet_drop_per_m2: float = 0.0
    box_temp: Optional[np.ndarray] = None         # (B,) wall temperatures, None = the world file's
    sun: Optional[np.ndarray] = None              # unit vector towards the sun
    thermal_noise_std: dict = field(default_factory=dict)   # robot id -> deg C
    thermal_offset: dict = field(default_factory=dict)      # robot id -> deg C


def sun_heated_normals(bmin: np.ndarray, bmax: np.ndarray, buildings: Sequence[str]) -> np.ndarray:
    """(B, 3) outward unit normals of the sun-heated surfaces (boxes tagged with a building; zero for the
    others): the box's thinnest axis, pointing away from its building's centre (roofs: up)."""
    n = np.zeros((len(bmin), 3))
    tags = np.asarray(list(buildings), dtype=object)
    for name in {b for b in buildings if b}:
        sel = np.nonzero(tags == name)[0]
        centre = 0.5 * (bmin[sel].min(axis=0) + bmax[sel].max(axis=0))
        for i in sel:
            ext = bmax[i] - bmin[i]
            k = int(np.argmin(ext))
            if k == 2:
                n[i, 2] = 1.0
            else:
                mid = 0.5 * (bmin[i, k] + bmax[i, k])
                n[i, k] = 1.0 if mid >= centre[k] else -1.0
    return n


def draw_unknowns(cfg: PhysicsConfig, rng: np.random.Generator, n_fires: int, robot_ids: Sequence[int],
                  bmin: np.ndarray, bmax: np.ndarray, box_temp: np.ndarray,
                  buildings: Sequence[str]) -> Unknowns:
    """One seed's physical unknowns, drawn in a fixed order (every model draws even when another is off
    would change nothing: each draws only when on)."""
    u = rng.uniform
    out = Unknowns(water_factor=np.ones(n_fires))
    if cfg.fire_water_factor is not None:
        out.water_factor = u(*cfg.fire_water_factor, size=n_fires)
    if cfg.jet_spot_factor is not None:
        out.jet_spot_factor = float(u(*cfg.jet_spot_factor))
    if cfg.jet_drop_per_m2 is not None:
        out.jet_drop_per_m2 = float(u(*cfg.jet_drop_per_m2))
    if cfg.wall_base_temp is not None:
        az, el = math.radians(u(*cfg.sun_azimuth_deg)), math.radians(u(*cfg.sun_elevation_deg))
        sun = np.array([math.sin(az) * math.cos(el), math.cos(az) * math.cos(el), math.sin(el)])
        normals = sun_heated_normals(bmin, bmax, buildings)
        heated = np.any(normals != 0.0, axis=1)
        base = float(u(*cfg.wall_base_temp))
        temps = base + cfg.wall_sun_gain * np.clip(normals @ sun, 0.0, None)
        lo, hi = cfg.wall_temp_limits
        out.box_temp = np.where(heated, np.clip(temps, lo, hi), box_temp)
        out.sun = sun
    for rid in robot_ids:
        if cfg.thermal_noise_std is not None:
            out.thermal_noise_std[rid] = float(u(*cfg.thermal_noise_std))
        if cfg.thermal_offset is not None:
            out.thermal_offset[rid] = float(u(*cfg.thermal_offset))
    return out


# ---------------------------------------------------------------------------------------------- profile
@dataclass(frozen=True)
class UncertaintyConfig:
    """One profile of the world file's `uncertainty:` section."""
    name: str = "ideal"
    gnss: GnssConfig = GnssConfig()
    laser: LaserConfig = LaserConfig()
    physics: PhysicsConfig = PhysicsConfig()

    @property
    def is_ideal(self) -> bool:
        return not (self.gnss.enabled or self.gnss.velocity_enabled or self.laser.enabled
                    or self.physics != PhysicsConfig())


def parse_profile(name: str, raw: Any) -> UncertaintyConfig:
    """Build a profile from its YAML mapping; raises UncertaintyError naming the bad entry."""
    w = f"uncertainty.{name}"
    raw = raw or {}
    if not isinstance(raw, dict):
        raise UncertaintyError(f"{w}: must be a mapping")
    unknown = set(raw) - {"gnss", "laser", "physics"}
    if unknown:
        raise UncertaintyError(f"{w}: unknown sections {sorted(unknown)} (known: gnss, laser, physics)")
    g, las, ph = (raw.get(k) or {} for k in ("gnss", "laser", "physics"))
    for k, v in (("gnss", g), ("laser", las), ("physics", ph)):
        if not isinstance(v, dict):
            raise UncertaintyError(f"{w}.{k}: must be a mapping")
    unknown = set(g) - set(GnssConfig.__dataclass_fields__)
    if unknown:
        raise UncertaintyError(f"{w}.gnss: unknown keys {sorted(unknown)}")
    denied = g.get("denied_indoors", False)
    if not isinstance(denied, bool):
        raise UncertaintyError(f"{w}.gnss.denied_indoors: must be true or false, got {denied!r}")
    gnss = GnssConfig(denied_indoors=denied, **{k: _num(g, k, f"{w}.gnss", getattr(GnssConfig, k)) for k in
                                                ("bias_xy_std", "bias_z_std", "tau", "white_xy_std", "white_z_std",
                                                 "indoor_vel_bias_std", "indoor_vel_bias_tau", "indoor_scale_std",
                                                 "vel_white_std", "vel_bias_std", "vel_bias_tau")})
    for k in ("tau", "indoor_vel_bias_tau", "vel_bias_tau"):
        if getattr(gnss, k) <= 0.0:
            raise UncertaintyError(f"{w}.gnss.{k}: must be > 0, got {getattr(gnss, k)}")
    laser = LaserConfig(**{k: _num(las, k, f"{w}.laser", 0.0) for k in
                           ("range_std_frac", "range_std_min", "nan_rate", "inf_rate")})
    if laser.nan_rate + laser.inf_rate > 1.0:
        raise UncertaintyError(f"{w}.laser: nan_rate + inf_rate must be <= 1")
    ranges = {}
    for k in ("fire_water_factor", "jet_spot_factor", "jet_drop_per_m2", "wall_base_temp",
              "thermal_noise_std", "thermal_offset"):
        ranges[k] = _range(ph, k, f"{w}.physics", (0, 0)) if k in ph else None
    for k in ("wall_temp_limits", "sun_azimuth_deg", "sun_elevation_deg"):
        if k in ph:
            ranges[k] = _range(ph, k, f"{w}.physics", (0, 0))
    ranges["wall_sun_gain"] = _num(ph, "wall_sun_gain", f"{w}.physics", 0.0)
    unknown = set(ph) - set(ranges)
    if unknown:
        raise UncertaintyError(f"{w}.physics: unknown keys {sorted(unknown)}")
    return UncertaintyConfig(name, gnss, laser, PhysicsConfig(**ranges))


def with_gnss_denied_indoors(cfg: UncertaintyConfig, denied: Optional[bool]) -> UncertaintyConfig:
    """The profile with its `gnss.denied_indoors` switch overridden (None: as the profile says)."""
    if denied is None or denied == cfg.gnss.denied_indoors:
        return cfg
    return dataclasses.replace(cfg, gnss=dataclasses.replace(cfg.gnss, denied_indoors=bool(denied)))


def profile(section: Any, name: str) -> UncertaintyConfig:
    """The named profile of a world file's `uncertainty:` section; `ideal` needs no entry (all off)."""
    section = section or {}
    if not isinstance(section, dict):
        raise UncertaintyError("uncertainty: must be a mapping of profile name -> models")
    if name not in section:
        if name == "ideal":
            return UncertaintyConfig("ideal")
        raise UncertaintyError(f"uncertainty profile '{name}' not in the world file (has: {sorted(section)})")
    return parse_profile(name, section[name])


class TrialUncertainty:
    """The running uncertainty of one trial: per-robot GNSS errors, the seed's unknowns, the laser model."""

    def __init__(self, cfg: UncertaintyConfig, seed: int, robot_ids: Sequence[int], n_fires: int,
                 bmin: np.ndarray, bmax: np.ndarray, box_temp: np.ndarray, buildings: Sequence[str]):
        self.cfg = cfg
        # One generator per model, never the simulation's own: a seed then gives the same GNSS error paths
        # whatever else draws (with one shared generator, the laser's draws, which depend on who subscribes
        # and when, changed every robot's GNSS path from run to run of the same seed).
        self.rng = np.random.default_rng([int(seed), 17])     # the seed's physical unknowns, drawn once
        self.unknowns = draw_unknowns(cfg.physics, self.rng, n_fires, list(robot_ids), bmin, bmax, box_temp,
                                      buildings)
        self.laser_rng = np.random.default_rng([int(seed), 18])
        self.gnss = ({rid: GnssError(cfg.gnss, np.random.default_rng([int(seed), 19, int(rid)]))
                      for rid in robot_ids} if cfg.gnss.enabled else {})
        self.velocity = ({rid: VelocityError(cfg.gnss, np.random.default_rng([int(seed), 20, int(rid)]))
                          for rid in robot_ids} if cfg.gnss.velocity_enabled else {})
        self.buildings = building_volumes(bmin, bmax, buildings)

    def step_gnss(self, dt: float, motion: Optional[Mapping[int, tuple]] = None) -> dict:
        """Advance every robot's position error; motion: robot id -> (true position, true velocity), which
        decides whether it is indoors (no fix) and how its dead reckoning drifts. Returns robot id -> change
        of its smooth error (x, y, z)."""
        out = {}
        for rid, g in self.gnss.items():
            pos, vel = (motion or {}).get(rid, (None, None))
            indoors = pos is not None and self.cfg.gnss.denied_indoors and inside_building(pos, self.buildings)
            out[rid] = g.step(dt, indoors, vel)
        for v in self.velocity.values():
            v.step(dt)
        return out

    def gnss_bias(self, rid: int) -> np.ndarray:
        """The smooth part of the robot's reported-position error (the GNSS bias outdoors, the dead-reckoned
        error indoors): a controller closing its loop on the reported pose is off by minus this."""
        g = self.gnss.get(rid)
        return g.error if g is not None else np.zeros(3)

    def gnss_valid(self, rid: int) -> bool:
        """False while the robot has no GNSS fix (indoors with `denied_indoors`)."""
        g = self.gnss.get(rid)
        return g is None or not g.denied

    def gnss_fix(self, rid: int) -> np.ndarray:
        g = self.gnss.get(rid)
        return g.fix() if g is not None else np.zeros(3)

    def velocity_error(self, rid: int) -> np.ndarray:
        """Error of one reported velocity of the robot (zero when the model is off)."""
        v = self.velocity.get(rid)
        return v.reading() if v is not None else np.zeros(3)

    def scan(self, ranges: np.ndarray, range_min: float, range_max: float) -> np.ndarray:
        if not self.cfg.laser.enabled:
            return ranges
        return corrupt_scan(ranges, self.cfg.laser, self.laser_rng, range_min, range_max)


__all__ = ["PROFILES", "UncertaintyError", "GnssConfig", "GaussMarkov", "GnssError", "VelocityError", "building_volumes",
           "inside_building", "with_gnss_denied_indoors", "LaserConfig",
           "corrupt_scan", "PhysicsConfig", "Unknowns", "draw_unknowns", "sun_heated_normals",
           "UncertaintyConfig", "parse_profile", "profile", "TrialUncertainty"]
