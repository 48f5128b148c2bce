"""The simulation without ROS: world, fires, robots, effects, collisions, faults; stepped by the node.

Why separate from the node: the physics, the refill rule and the scoring are tested with pytest at full
speed, and benchmarks can time the sensor models alone.
"""
from __future__ import annotations

import dataclasses
import math
import threading
from dataclasses import dataclass
from typing import Optional

import numpy as np

from . import constants as C
from .altimeter import altimeter_reading
from .effects import JetResult, WaterLedger, shoot
from .fires import FireSet
from .rgbd import RGBDCamera
from .robot import Robot
from .thermal import DOWNWARD, FORWARD, ThermalCamera
from .uncertainty import TrialUncertainty, UncertaintyConfig
from .world import World

FAULT_KINDS = ("crash", "comm_loss", "sensor_failure")


@dataclass
class Event:
    """Something worth a log line and a score entry (crash, extinguish, refill, blanket drop)."""
    time: float
    text: str


@dataclass
class Blanket:
    """A released blanket lying on the ground (for markers)."""
    position: np.ndarray
    fire: Optional[int]


class Simulation:
    """All state of a trial. Every public method must be called with `self.lock` held (the node does)."""

    def __init__(self, world: World, seed: int = 0, pose_noise_std: float = 0.0, wind: bool = True,
                 uncertainty: Optional[UncertaintyConfig] = None):
        self.seed = seed
        self.rng = np.random.default_rng(seed + 1000)
        self.fires = FireSet(world, seed)
        # the trial's uncertainty (None or `ideal`: none, exactly the simulator without it)
        cfg = uncertainty if uncertainty is not None and not uncertainty.is_ideal else None
        self.uncertainty = None if cfg is None else TrialUncertainty(
            cfg, seed, [r.id for r in world.robots], len(self.fires.fires), world.bmin, world.bmax,
            world.box_temp, world.box_building or [""] * len(world.bmin))
        if self.uncertainty is not None:
            unk = self.uncertainty.unknowns
            if unk.box_temp is not None:
                world = dataclasses.replace(world, box_temp=unk.box_temp)
            for f, k in zip(self.fires.fires, unk.water_factor):
                f.litres_needed = C.LITRES_PER_FIRE * float(k)
        self.world = world
        self.robots: dict[int, Robot] = {s.id: Robot(s, world) for s in world.robots}
        if self.uncertainty is not None:
            for r in self.robots.values():
                r.gnss_bias = self.uncertainty.gnss_bias(r.id).copy()
        self.time = 0.0
        self.lock = threading.RLock()
        self.pose_noise_std = pose_noise_std
        self.wind = wind
        self.events: list[Event] = []
        self.jets: dict[int, JetResult] = {}
        self.water = WaterLedger(self.fires)   # where each robot's water went (the referee's, /sim/water)
        self.blankets: list[Blanket] = []
        self.thermal = {FORWARD: ThermalCamera(FORWARD), DOWNWARD: ThermalCamera(DOWNWARD)}
        self.rgbd = RGBDCamera()
        self._cache: dict = {}   # (robot id, sensor) -> (key, frame): a robot that did not move sees the same
        # the altimeters' noise (any profile but `ideal`): a generator of their own, so that a seed's other
        # draws do not depend on who listens to the altimeters
        self.altimeter_rng = None if self.uncertainty is None else np.random.default_rng([int(seed), 23])

    # ------------------------------------------------------------------ stepping
    def step(self, dt: float) -> None:
        """Advance everything by dt seconds of sim time."""
        self.time += dt
        rng = self.rng if self.wind else _NO_WIND
        if self.uncertainty is not None and (self.uncertainty.gnss or self.uncertainty.velocity):
            self._follow_gnss_bias(dt)
        for r in self.robots.values():
            before = r.refills
            r.step(dt, self.time, rng)
            if r.refills != before:
                self.events.append(Event(self.time, f"robot {r.id}: reset at home (tank refilled / new blanket)"))
        self.jets.clear()
        for r in self.robots.values():
            litres = r.pump(dt)
            if litres > 0.0:
                p, d = r.nozzle()
                unk = self.uncertainty.unknowns if self.uncertainty is not None else None
                jet = shoot(self.world, self.fires, p, d) if unk is None else shoot(
                    self.world, self.fires, p, d, unk.jet_spot_factor, unk.jet_drop_per_m2)
                self.jets[r.id] = jet
                into = 0.0
                if jet.fire is not None and jet.share > 0.0:
                    was = self.fires.fires[jet.fire].extinguished
                    into = self.fires.add_water(jet.fire, litres * jet.share, self.time)
                    f = self.fires.fires[jet.fire]
                    if f.extinguished and not was:
                        self.events.append(Event(self.time, f"fire {f.holder.id} extinguished by robot {r.id}"))
                self.water.add(r.id, litres, into, jet, p, d)
            if r.pump_on and r.water <= 0.0:
                r.pump_on = False
                self.events.append(Event(self.time, f"robot {r.id}: tank empty, pump stopped"))
        self._collisions()

    def _follow_gnss_bias(self, dt: float) -> None:
        """Every robot's reported-position error changes (the GNSS bias wanders; indoors without GNSS the
        dead reckoning drifts); a controller that holds or flies to a set-point in the reported frame moves
        its true set-point by minus that change (a landing keeps its height, the UGV its z)."""
        motion = {rid: (r.pos, r.vel) for rid, r in self.robots.items()}
        for rid, delta in self.uncertainty.step_gnss(dt, motion).items():
            r = self.robots[rid]
            r.gnss_bias = self.uncertainty.gnss_bias(rid).copy()
            if r.crashed:
                continue
            if r.is_uav and r.flying and r.mode in ("goto", "idle", "takeoff"):
                r.goal = r.goal - delta
            elif (r.is_uav and r.mode == "land") or (not r.is_uav and r.mode == "goto"):
                r.goal = r.goal - delta * (1.0, 1.0, 0.0)

    def _collisions(self) -> None:
        alive = [r for r in self.robots.values() if not r.crashed]
        if not alive:
            return
        # building: flying UAVs and the UGV (a landed UAV rests on its support surface)
        movers = [r for r in alive if r.flying or not r.is_uav]
        if movers:
            centres = np.array([r.body_centre() for r in movers])
            radii = np.array([r.radius for r in movers])
            hit = self.world.sphere_hits_building(centres, radii)
            for r, h in zip(movers, hit):
                if h:
                    self._crash(r, "hit the building")
        for r in alive:
            if r.flying and r.pos[2] < -1e-3 and not r.crashed:
                self._crash(r, "hit the ground")
            elif not self.world.inside_arena(r.pos) and not r.crashed:
                self._crash(r, "left the arena")
        alive = [r for r in alive if not r.crashed]
        if len(alive) > 1:
            c = np.array([r.body_centre() for r in alive])
            rad = np.array([r.radius for r in alive])
            d = np.linalg.norm(c[:, None, :] - c[None, :, :], axis=2)
            close = d < (rad[:, None] + rad[None, :])
            np.fill_diagonal(close, False)
            for i, j in zip(*np.nonzero(np.triu(close))):
                self._crash(alive[i], f"collided with robot {alive[j].id}")
                self._crash(alive[j], f"collided with robot {alive[i].id}")

    def _crash(self, r: Robot, reason: str) -> None:
        if r.crashed:
            return
        where = f"({r.pos[0]:.2f}, {r.pos[1]:.2f}, {r.pos[2]:.2f}) yaw {r.yaw:.2f}"
        r.crash(reason)
        self.events.append(Event(self.time, f"robot {r.id} crashed: {reason} at {where}"))

    # ------------------------------------------------------------------ actuators
    def start_pump(self, rid: int) -> tuple[bool, str]:
        r = self.robots[rid]
        if r.crashed:
            return False, f"robot {rid} has crashed"
        if r.spec.payload != C.PAYLOAD_WATER:
            return False, f"robot {rid} carries no water pump"
        if r.water <= 0.0:
            return False, "tank empty"
        r.pump_on = True
        return True, f"pump on, {r.water:.2f} L left"

    def stop_pump(self, rid: int) -> tuple[bool, str]:
        r = self.robots[rid]
        if r.spec.payload != C.PAYLOAD_WATER:
            return False, f"robot {rid} carries no water pump"
        r.pump_on = False
        return True, f"pump off, {r.water:.2f} L left"

    def release_blanket(self, rid: int) -> tuple[bool, str]:
        r = self.robots[rid]
        if r.crashed:
            return False, f"robot {rid} has crashed"
        if r.spec.payload != C.PAYLOAD_BLANKET:
            return False, f"robot {rid} carries no blanket"
        if not r.blanket:
            return False, "no blanket attached (reset at home for a new one)"
        r.blanket = False
        height = r.pos[2] - self.world.support_height(r.pos[0], r.pos[1], r.pos[2])
        i = self.fires.drop_blanket(r.pos[0], r.pos[1], height, self.time)
        self.blankets.append(Blanket(np.array([r.pos[0], r.pos[1], 0.0]), i))
        if i is not None and self.fires.fires[i].active:
            self.events.append(Event(self.time, f"fire {self.fires.fires[i].holder.id} covered by robot {rid}"))
            return True, "blanket released on the fire"
        return True, "blanket released"

    # ------------------------------------------------------------------ faults
    def inject_fault(self, rid: int, kind: str, duration: float) -> tuple[bool, str]:
        """Test hook: crash a robot, cut its communications or its sensors for `duration` s (0 = forever)."""
        if rid not in self.robots:
            return False, f"unknown robot id {rid} (known: {sorted(self.robots)})"
        if kind not in FAULT_KINDS:
            return False, f"unknown fault kind '{kind}' (known: {', '.join(FAULT_KINDS)})"
        if not math.isfinite(duration) or duration < 0.0:
            return False, f"duration must be >= 0, got {duration}"
        r = self.robots[rid]
        until = math.inf if duration == 0.0 else self.time + duration
        if kind == "crash":
            self._crash(r, "injected fault")
        elif kind == "comm_loss":
            r.comm_loss_until = until
        else:
            r.sensor_fail_until = until
        self.events.append(Event(self.time, f"fault {kind} injected on robot {rid} for {duration:g} s"))
        return True, f"{kind} injected on robot {rid}"

    # ------------------------------------------------------------------ outputs
    def reported_pose(self, r: Robot) -> np.ndarray:
        """Pose the robot reports (x, y, z, yaw): the truth plus optional Gaussian noise."""
        p = np.array([r.pos[0], r.pos[1], r.pos[2], r.yaw])
        if self.pose_noise_std > 0.0 and not r.crashed:
            p[:3] += self.rng.normal(0.0, self.pose_noise_std, 3)
        if self.uncertainty is not None and self.uncertainty.gnss:
            p[:3] += self.uncertainty.gnss_fix(r.id)   # GNSS error (a crashed robot's receiver still reports)
        return p

    def reported_velocity(self, r: Robot) -> np.ndarray:
        """Velocity the robot reports (vx, vy, vz in the arena frame): the truth plus the autopilot's
        velocity-estimate error (uncertainty.VelocityError) when the profile has one."""
        v = np.asarray(r.vel, dtype=float)
        if self.uncertainty is not None and self.uncertainty.velocity and not r.crashed:
            v = v + self.uncertainty.velocity_error(r.id)
        return v

    def gnss_valid(self, r: Robot) -> bool:
        """Whether the robot's reported pose follows a GNSS fix now (False indoors with `denied_indoors`)."""
        return self.uncertainty is None or self.uncertainty.gnss_valid(r.id)

    def _cached(self, r: Robot, sensor: str, fn):
        """Reuse the last frame of this sensor while the robot's pose and the fires are unchanged."""
        key = (r.pos[0], r.pos[1], r.pos[2], r.yaw, self.fires.version)
        hit = self._cache.get((r.id, sensor))
        if hit is not None and hit[0] == key:
            return hit[1]
        frame = fn()
        self._cache[(r.id, sensor)] = (key, frame)
        return frame

    def laser(self, r: Robot) -> np.ndarray:
        lz = r.pos[2] + r.laser_z + C.LASER_OFFSET[2]
        clean = self._cached(r, "laser", lambda: self.world.laser_scan(r.pos[0], r.pos[1], lz, r.yaw))
        if self.uncertainty is None:
            return clean
        return self.uncertainty.scan(clean, C.LASER_RANGE_MIN, C.LASER_RANGE_MAX)

    def altimeter(self, r: Robot) -> float:
        """The downward altimeter's reading (altimeter.py): the TRUE height of base_link above the surface
        below (the highest box top under it, else the ground), with the sensor's noise unless `ideal`."""
        height = r.pos[2] - self.world.support_height(r.pos[0], r.pos[1], r.pos[2])
        return altimeter_reading(height, self.altimeter_rng)

    def thermal_frame(self, r: Robot, direction: int) -> np.ndarray:
        cam = self.thermal[direction]
        clean = self._cached(r, f"thermal{direction}",
                             lambda: cam.render_clean(self.world, self.fires, r.sensor_base(), r.yaw))
        if self.uncertainty is not None:     # this camera's own noise and calibration offset (uncertainty.py)
            unk = self.uncertainty.unknowns
            std = unk.thermal_noise_std.get(r.id, cam.noise_std)
            frame = clean + unk.thermal_offset.get(r.id, 0.0)
            return frame + self.rng.normal(0.0, std, clean.shape) if std > 0 else frame
        return clean + self.rng.normal(0.0, cam.noise_std, clean.shape) if cam.noise_std > 0 else clean

    def rgbd_frame(self, r: Robot) -> tuple[np.ndarray, np.ndarray]:
        return self._cached(r, "rgbd", lambda: self.rgbd.render(self.world, self.fires, r.sensor_base(), r.yaw))

    def score(self) -> dict:
        done = [f for f in self.fires.fires if f.extinguished]
        return {"score": self.fires.score(), "max_score": self.fires.max_score(),
                "extinguished": [(f.holder.id, f.extinguish_time) for f in done],
                "elapsed": self.time, "time_left": self.world.trial_duration - self.time,
                "crashed": [r.id for r in self.robots.values() if r.crashed]}

    def pop_events(self) -> list[Event]:
        ev, self.events = self.events, []
        return ev


class _NoWind:
    """A stand-in generator giving zero gusts (wind disabled)."""

    @staticmethod
    def standard_normal(n: int) -> np.ndarray:
        return np.zeros(n)


_NO_WIND = _NoWind()
__all__ = ["Simulation", "FAULT_KINDS", "Event", "Blanket"]
