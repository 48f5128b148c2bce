"""Kinematic robot model with the UAL state machine (UAVs) or a ground-vehicle variant (UGV).

Why kinematic: the original team's "light" UAL backend moves the UAV straight to the set-point under speed
limits; agents were developed against that. Commands return (ok, message) so that the ROS adapter can log a
clear error for bad requests (take-off while flying, NaN, waypoint outside the arena) instead of crashing.
"""
from __future__ import annotations

import math
import numpy as np

from . import constants as C
from .world import RobotSpec, World

OK = (True, "")


def wrap(a: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


class Robot:
    """State of one robot; all methods run under the simulator's lock."""

    def __init__(self, spec: RobotSpec, world: World):
        self.spec = spec
        self.id = spec.id
        self.is_uav = spec.kind == "uav"
        self.world = world
        self.pos = spec.home.astype(float).copy()
        self.yaw = float(spec.yaw)
        self.vel = np.zeros(3)
        self.yaw_rate = 0.0
        self.state = C.LANDED_DISARMED if self.is_uav else C.LANDED_ARMED
        self.mode = "idle"                 # idle | goto | velocity | takeoff | land
        self.goal = self.pos.copy()
        self.goal_yaw = self.yaw
        self.vel_cmd = np.zeros(4)         # vx, vy, vz, yaw rate (arena frame)
        self.vel_cmd_time = -1e9
        self.crashed = False
        self.crash_reason = ""
        self.water = C.TANK_LITRES if spec.payload == C.PAYLOAD_WATER else 0.0
        self.blanket = spec.payload == C.PAYLOAD_BLANKET
        self.pump_on = False
        self.comm_loss_until = -1.0
        self.sensor_fail_until = -1.0
        self.ual_home = self.pos.copy()
        self.refill_timer = 0.0
        self.refills = 0
        self.wind = np.zeros(2)
        self.wind_error = np.zeros(2)     # position error the gusts cause (bounded by the controller)
        # GNSS bias of the reported pose (uncertainty.py): waypoints are commanded in the reported frame, so
        # the true set-point is the command minus this (Simulation keeps it and shifts goals as it wanders)
        self.gnss_bias = np.zeros(3)
        self.radius = C.UAV_RADIUS if self.is_uav else C.UGV_RADIUS
        self.body_offset = C.UAV_BODY_OFFSET_Z if self.is_uav else C.UGV_BODY_OFFSET_Z
        self.max_vxy = C.UAV_MAX_VXY if self.is_uav else C.UGV_MAX_V
        self.max_vz = C.UAV_MAX_VZ if self.is_uav else 0.0
        self.max_wz = C.UAV_MAX_YAW_RATE if self.is_uav else C.UGV_MAX_YAW_RATE
        self.sensor_z = 0.0 if self.is_uav else C.UGV_MAST_Z      # thermal and RGB-D cameras
        self.laser_z = 0.0 if self.is_uav else C.UGV_LASER_Z      # 2D laser (UGV: low on the chassis)

    # ------------------------------------------------------------------ helpers
    @property
    def flying(self) -> bool:
        return self.is_uav and self.state in C.FLYING_STATES

    @property
    def moving(self) -> bool:
        return self.mode in ("goto", "velocity", "takeoff", "land")

    def body_centre(self) -> np.ndarray:
        return self.pos + np.array([0.0, 0.0, self.body_offset])

    def sensor_base(self) -> np.ndarray:
        """Where the camera mounts (thermal, RGB-D) are measured from: base_link, on the UGV the mast top."""
        return self.pos + np.array([0.0, 0.0, self.sensor_z])

    def comm_ok(self, now: float) -> bool:
        return now >= self.comm_loss_until

    def sensors_ok(self, now: float) -> bool:
        return now >= self.sensor_fail_until and not self.crashed

    def _alive(self) -> tuple[bool, str]:
        if self.crashed:
            return False, f"robot {self.id} has crashed ({self.crash_reason}); it accepts no commands"
        return OK

    def _check_goal(self, x: float, y: float, z: float, yaw: float) -> tuple[bool, str]:
        vals = (x, y, z, yaw)
        if not all(math.isfinite(v) for v in vals):
            return False, f"non-finite waypoint {vals}"
        p = np.array([x, y, z if self.is_uav else self.world.arena_min[2]])
        if not self.world.inside_arena(p):
            return False, (f"waypoint ({x:.2f}, {y:.2f}, {z:.2f}) is outside the arena "
                           f"{self.world.arena_min.tolist()} - {self.world.arena_max.tolist()}")
        return OK

    # ------------------------------------------------------------------ commands (UAL)
    def take_off(self, height: float) -> tuple[bool, str]:
        ok = self._alive()
        if not ok[0]:
            return ok
        if not self.is_uav:
            return False, "the UGV cannot take off"
        if not math.isfinite(height) or height <= 0.0:
            return False, f"take_off height must be a positive number, got {height}"
        if self.state not in (C.LANDED_DISARMED, C.LANDED_ARMED):
            return False, f"take_off refused: robot {self.id} is not landed (state {self.state})"
        target = self.pos + np.array([0.0, 0.0, height])
        if not self.world.inside_arena(target):
            return False, f"take_off to z {target[2]:.2f} would leave the arena"
        self.goal, self.goal_yaw = target, self.yaw
        self.state, self.mode = C.TAKING_OFF, "takeoff"
        return OK

    def land(self) -> tuple[bool, str]:
        ok = self._alive()
        if not ok[0]:
            return ok
        if not self.is_uav:
            return False, "the UGV cannot land"
        if not self.flying:
            return False, f"land refused: robot {self.id} is not flying (state {self.state})"
        z = self.world.support_height(self.pos[0], self.pos[1], self.pos[2])
        self.goal = np.array([self.pos[0], self.pos[1], z])
        self.goal_yaw = self.yaw
        self.state, self.mode = C.LANDING, "land"
        return OK

    def go_to(self, x: float, y: float, z: float, yaw: float) -> tuple[bool, str]:
        ok = self._alive()
        if not ok[0]:
            return ok
        ok = self._check_goal(x, y, z, yaw)
        if not ok[0]:
            return ok
        if self.is_uav and self.state not in (C.FLYING_AUTO, C.FLYING_MANUAL):
            return False, f"go_to_waypoint refused: robot {self.id} is not flying (state {self.state})"
        self.goal = np.array([x, y, z if self.is_uav else self.pos[2]]) - self.gnss_bias * (1.0, 1.0, self.is_uav)
        self.goal_yaw = wrap(yaw)
        self.mode = "goto"
        if self.is_uav:
            self.state = C.FLYING_AUTO
        else:
            self.state = C.FLYING_AUTO
        return OK

    def set_velocity(self, v: np.ndarray, now: float) -> tuple[bool, str]:
        """v = (vx, vy, vz, yaw rate) in the arena frame; clamped to the speed limits."""
        ok = self._alive()
        if not ok[0]:
            return ok
        if not np.all(np.isfinite(v)):
            return False, f"non-finite velocity {v.tolist()}"
        if self.is_uav and self.state not in (C.FLYING_AUTO, C.FLYING_MANUAL):
            return False, f"set_velocity ignored: robot {self.id} is not flying (state {self.state})"
        v = v.astype(float).copy()
        nxy = math.hypot(v[0], v[1])
        if nxy > self.max_vxy:
            v[:2] *= self.max_vxy / nxy
        v[2] = float(np.clip(v[2], -self.max_vz, self.max_vz)) if self.is_uav else 0.0
        v[3] = float(np.clip(v[3], -self.max_wz, self.max_wz))
        self.vel_cmd, self.vel_cmd_time, self.mode = v, now, "velocity"
        self.state = C.FLYING_AUTO
        return OK

    def set_home(self, set_z: bool) -> tuple[bool, str]:
        home = self.pos.copy()
        if not set_z:
            home[2] = self.ual_home[2]
        self.ual_home = home
        return OK

    def recover_from_manual(self) -> tuple[bool, str]:
        if self.state == C.FLYING_MANUAL:
            self.state = C.FLYING_AUTO
        return OK

    def goal_reached(self) -> bool:
        """True when the last position command is done (used by blocking service calls)."""
        return self.mode not in ("goto", "takeoff", "land")

    def crash(self, reason: str) -> None:
        """Crash: the robot falls to the surface below and stays there, deaf (state UNINITIALIZED)."""
        if self.crashed:
            return
        self.crashed, self.crash_reason = True, reason
        self.pos[2] = self.world.support_height(self.pos[0], self.pos[1], self.pos[2])
        self.vel[:] = 0.0
        self.yaw_rate = 0.0
        self.pump_on = False
        self.mode = "idle"
        self.state = C.UNINITIALIZED

    # ------------------------------------------------------------------ motion
    def step(self, dt: float, now: float, rng: np.random.Generator) -> None:
        """Advance the kinematics by dt seconds."""
        old, old_yaw = self.pos.copy(), self.yaw
        if self.crashed:
            self.vel[:] = 0.0
            return
        if self.mode in ("goto", "takeoff", "land"):
            vz = self.max_vz if self.mode != "land" else min(self.max_vz, 0.8)
            if self._move_towards(self.goal, self.goal_yaw, self.max_vxy, vz, dt):
                self._arrived()
        elif self.mode == "velocity":
            if now - self.vel_cmd_time > C.VELOCITY_CMD_TIMEOUT:
                self.mode, self.goal = "idle", self.pos.copy()
            else:
                self.pos += self.vel_cmd[:3] * dt
                self.yaw = wrap(self.yaw + self.vel_cmd[3] * dt)
        elif self.flying:
            # position hold: a first-order pull back to the last set-point (what gusts push against)
            self.pos += (self.goal - self.pos) * min(1.0, C.HOLD_GAIN * dt)
        if self.flying:
            self._wind(dt, rng)
        if not self.is_uav and self.mode == "idle":
            self.state = C.LANDED_ARMED
        self.vel = (self.pos - old) / dt
        self.yaw_rate = wrap(self.yaw - old_yaw) / dt
        self._refill(dt)

    def _move_towards(self, goal: np.ndarray, goal_yaw: float, vxy: float, vz: float, dt: float) -> bool:
        delta = goal - self.pos
        dxy, dz = math.hypot(delta[0], delta[1]), abs(delta[2])
        s = 1.0
        if dxy > 1e-9:
            s = min(s, vxy * dt / dxy)
        if dz > 1e-9:
            s = min(s, vz * dt / dz) if vz > 0 else 0.0 if self.is_uav else s
        self.pos += s * delta
        dyaw = wrap(goal_yaw - self.yaw)
        self.yaw = wrap(self.yaw + float(np.clip(dyaw, -self.max_wz * dt, self.max_wz * dt)))
        # done when this step landed exactly on the goal position and the heading is within tolerance
        return s >= 1.0 and abs(wrap(goal_yaw - self.yaw)) < C.GOAL_TOL_YAW

    def _arrived(self) -> None:
        if self.mode == "land":
            self.pos[2] = self.goal[2]
            self.state = C.LANDED_DISARMED
            self.pump_on = False
        elif self.mode == "takeoff":
            self.state = C.FLYING_AUTO
        self.mode = "idle"
        if not self.is_uav:
            self.state = C.LANDED_ARMED

    def _wind(self, dt: float, rng: np.random.Generator) -> None:
        """Gusts near the first floor close to the tower, fought by the position controller.

        The gust is an Ornstein-Uhlenbeck velocity; the controller turns it into a bounded position error
        (first order: error' = gust - HOLD_GAIN * error), and only the change of that error moves the UAV.
        So the UAV wobbles about its set-point or path by a few tens of centimetres but never drifts away.
        """
        z0, z1 = C.WIND_Z_RANGE
        near = False
        if z0 <= self.pos[2] <= z1 and C.WIND_GUST_STD > 0.0:
            near = len(self.world.boxes_near(self.pos, C.WIND_MAX_DIST)) > 0
        if near:
            a = math.exp(-dt / C.WIND_GUST_TAU)
            self.wind = a * self.wind + math.sqrt(1.0 - a * a) * C.WIND_GUST_STD * rng.standard_normal(2)
        else:
            self.wind[:] = 0.0
        prev = self.wind_error.copy()
        self.wind_error += (self.wind - C.HOLD_GAIN * self.wind_error) * dt
        self.pos[:2] += self.wind_error - prev

    def _refill(self, dt: float) -> None:
        """The human reset of the competition: landed, disarmed near home for REFILL_TIME -> full tank, blanket."""
        if (self.is_uav and self.state == C.LANDED_DISARMED
                and np.linalg.norm(self.pos[:2] - self.spec.home[:2]) <= C.REFILL_RADIUS):
            before = self.refill_timer
            self.refill_timer += dt
            if before < C.REFILL_TIME <= self.refill_timer:
                self.refills += 1
            if self.refill_timer >= C.REFILL_TIME:
                if self.spec.payload == C.PAYLOAD_WATER:
                    self.water = C.TANK_LITRES
                else:
                    self.blanket = True
        else:
            self.refill_timer = 0.0

    def pump(self, dt: float) -> float:
        """Litres leaving the nozzle during dt (0 when the pump is off or the tank empty)."""
        if not self.pump_on or self.crashed:
            return 0.0
        out = min(self.water, C.PUMP_FLOW * dt)
        self.water -= out
        if self.water <= 1e-9:
            self.water = 0.0
        return out

    def nozzle(self) -> tuple[np.ndarray, np.ndarray]:
        """Nozzle position and unit direction (base_link +x) in the arena frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        ox, oy, oz = C.NOZZLE_OFFSET
        p = self.pos + np.array([c * ox - s * oy, s * ox + c * oy, oz + (0.0 if self.is_uav else C.UGV_NOZZLE_Z)])
        return p, np.array([c, s, 0.0])
