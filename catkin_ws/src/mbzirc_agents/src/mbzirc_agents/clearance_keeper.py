"""ClearanceKeeper: a UAV agent's use of the clearance guard (clearance.py) on its motion commands.

It feeds the guard with the downward altimeter (`altimeter`, sensor_msgs/Range) and the GNSS pose of the
reading's time, and with the autopilot's velocity (`ual/velocity`, geometry_msgs/TwistStamped: its vertical
part tracks the true height while a hold lasts, clearance.py), bounds every go-to set-point and velocity the agent sends while flying (not while taking
off or landing: the UAL owns those), and watches the held set-point at the control rate: the vertical GNSS
error wanders while the UAV holds, which moves its true height, so a set-point that has become too low is
sent again, raised. A stale or invalid altimeter gives a throttled error and the guard's GNSS fallback.
"""
from __future__ import annotations

import math
import threading
from typing import Any, Callable, Optional, Sequence

import numpy as np
from geometry_msgs.msg import TwistStamped
from sensor_msgs.msg import Range

from . import constants as C
from .clearance import ClearanceConfig, ClearanceGuard

VELOCITY_HOLD_AFTER = 0.5    # s: the UAL stops and holds this long after the last velocity command


class ClearanceKeeper:
    """Owned by a UavAgent. `send_raw(x, y, z, yaw)`: the agent's unguarded go-to (RobotAgent's)."""

    def __init__(self, agent: Any, send_raw: Callable[[float, float, float, float], None]) -> None:
        self.agent = agent
        self.send_raw = send_raw
        p = agent.p
        self.enabled = bool(p.clearance_guard)
        self.guard = ClearanceGuard(ClearanceConfig(min_clearance=p.min_clearance,
                                                    fallback_margin=p.clearance_fallback_margin,
                                                    max_age=p.altimeter_max_age),
                                    C.BUILDINGS, C.FLOOR_HEIGHTS, agent.arena[2])
        self.lock = threading.RLock()
        self.request: Optional[tuple] = None     # (x, y, z, yaw) the task asked to hold / fly to
        self.sent_z: Optional[float] = None      # the z the UAL was sent for it
        self.velocity_time = -math.inf           # backend time of the last velocity command
        self.raised = 0                          # set-points raised so far (tests, log)
        agent.iface.add_subscriber(None, 'altimeter', Range, self._on_range)
        agent.iface.add_subscriber(None, 'ual/velocity', TwistStamped, self._on_velocity)

    # ---- input ---------------------------------------------------------------------------------------------
    def _on_range(self, msg: Range) -> None:
        self._feed(msg, lambda stamp, gnss: self.guard.on_reading(msg.range, stamp, gnss[:3]))

    def _on_velocity(self, msg: TwistStamped) -> None:
        self._feed(msg, lambda stamp, gnss: self.guard.on_velocity(msg.twist.linear.z, stamp, gnss[2]))

    def _feed(self, msg: Any, to_guard: Callable[[float, np.ndarray], None]) -> None:
        """to_guard(stamp, GNSS pose at the stamp) of a sensor message, under the lock; nothing before a pose."""
        a = self.agent
        if a.pose is None:
            return
        stamp = msg.header.stamp.to_sec() or a.backend.now()
        gnss = a.pose_at(stamp)
        with self.lock:
            to_guard(stamp, gnss)

    def _active(self) -> bool:
        """The guard bounds commands while the UAL flies under the agent's commands."""
        return self.enabled and self.agent.ual_state in (C.UAL_FLYING_AUTO, C.UAL_FLYING_MANUAL)

    def vertical_error(self) -> Optional[float]:
        """The vertical GNSS error e (GNSS z - true z) while the altimeter gives a fresh estimate, else None:
        the true height of base_link is the GNSS height minus e (e.g. to centre in a window)."""
        with self.lock:
            g = self.guard
            return g.error if g.fresh(self.agent.backend.now()) else None

    def true_height(self) -> Optional[float]:
        """The true height (arena z of base_link) by the guard (clearance.py `true_z`: while a hold is tracked,
        by the vertical velocity since its start; else the GNSS height less a fresh e); None without either."""
        return self.true_height_of(float(self.agent.position(wait=0.0)[2]))

    def true_height_of(self, gnss_z: float) -> Optional[float]:
        """true_height() of a reported GNSS height gnss_z (a pose message's), None without an estimate."""
        with self.lock:
            return self.guard.true_z(gnss_z, self.agent.backend.now())

    def tracking(self) -> bool:
        """True while a hold's true height is tracked by the vertical velocity (clearance.py)."""
        with self.lock:
            return self.guard.tracking(self.agent.backend.now())

    def hold_estimate(self, why: str) -> bool:
        """From now until release_estimate(), altimeter readings are ignored and the vertical error estimate is
        held as it is, tracked by the vertical velocity (clearance.py, `hold`), e.g. while the UAV's frame is in
        an opening whose sill the altimeter would take for a floor. False (warned) when there is no fresh
        estimate to hold."""
        a = self.agent
        with self.lock:
            held = self.guard.hold(a.backend.now(), float(a.position(wait=0.0)[2]) if a.pose is not None else None)
        if not held:
            a.backend.logwarn(f'clearance guard: no fresh altimeter estimate to hold while {why}')
        return held

    def release_estimate(self) -> None:
        """End a hold_estimate (no-op without one)."""
        with self.lock:
            self.guard.release()

    # ---- commands ------------------------------------------------------------------------------------------
    def set_point_z(self, x: float, y: float, z: float) -> float:
        """The z the UAL is (or would be) sent for a requested (x, y, z)."""
        if not self._active():
            return float(z)
        with self.lock:
            return self.guard.safe_set_point_z(x, y, z, self.agent.backend.now())

    def waypoint(self, x: float, y: float, z: float, yaw: float) -> None:
        """Send a go-to with its z raised to the bound when needed; it becomes the held set-point."""
        with self.lock:
            z_sent = self.set_point_z(x, y, z)
            if z_sent > z + 1e-6:
                self._note_raise(z, z_sent)
            self.request, self.sent_z = (float(x), float(y), float(z), float(yaw)), z_sent
            self.send_raw(x, y, z_sent, yaw)

    def velocity(self, v: Sequence[float]) -> np.ndarray:
        """v with its vertical part bounded (measured height, or the GNSS fallback)."""
        v = np.array(v, dtype=float)
        with self.lock:
            self.velocity_time = self.agent.backend.now()
            self.request = self.sent_z = None                # the UAL follows velocities now
            if self._active() and self.agent.pose is not None:
                vz = self.guard.safe_vz(v[2], self.agent.position(wait=0.0)[:3], self.velocity_time)
                if vz > v[2] + 1e-6:
                    self.agent.backend.loginfo_throttle(
                        5.0, f'clearance guard: vertical speed {v[2]:+.2f} -> {vz:+.2f} m/s (keeping '
                             f'{self.guard.cfg.min_clearance:.2f} m above the surface below)')
                v[2] = vz
        return v

    def _note_raise(self, z: float, z_sent: float) -> None:
        self.raised += 1
        g, now = self.guard, self.agent.backend.now()
        why = (f'GNSS height error {g.error:+.2f} m' if g.fresh(now) and g.error is not None
               else f'altimeter unusable, +{g.cfg.fallback_margin:.1f} m margin')
        self.agent.backend.loginfo_throttle(
            2.0, f'clearance guard: set-point z {z:.2f} raised to {z_sent:.2f} ({why}; keeping '
                 f'{g.cfg.min_clearance:.2f} m above the surface below)')

    # ---- watch ---------------------------------------------------------------------------------------------
    def step(self) -> None:
        """At the control rate: warn about a useless altimeter while flying; re-send a held set-point whose
        bound rose by half the hysteresis (it aims that much above the clearance: re-sent before the true
        height reaches the clearance) or fell by the whole of it (higher than needed)."""
        a = self.agent
        if not self.enabled:
            return
        if a.ual_state not in (C.UAL_FLYING_AUTO, C.UAL_FLYING_MANUAL):
            with self.lock:
                self.request = self.sent_z = None           # take-off, landing, landed: the UAL's own
            return
        now = a.backend.now()
        with self.lock:
            problem = self.guard.problem(now)
        if problem:
            a.backend.logerr_throttle(5.0, f'altimeter: {problem}: the clearance guard keeps '
                                           f'{self.guard.cfg.fallback_margin:.1f} m more on the GNSS height')
        if a.pose is None or a.pose_in_doubt() or now - self.velocity_time < VELOCITY_HOLD_AFTER:
            return
        with self.lock:
            if self.request is None:                          # holding where a take-off / velocities left it
                p = a.position(wait=0.0)
                self.request, self.sent_z = (p[0], p[1], p[2], p[3]), p[2]
            x, y, z, yaw = self.request
            bound = self.guard.min_set_point_z(x, y, z, now)
            want = max(z, bound)
            hyst = self.guard.cfg.hysteresis
            if bound > self.sent_z + 0.5 * hyst or (self.sent_z > z + 1e-6 and self.sent_z - want > hyst):
                if want > z + 1e-6:
                    self._note_raise(z, want)
                self.sent_z = want
                self.send_raw(x, y, want, yaw)

    def run(self) -> None:
        """The watch loop (its own thread), until shutdown; an error is logged, never ends the agent."""
        a = self.agent
        while not a.backend.is_shutdown():
            try:
                self.step()
            except Exception as e:  # noqa: BLE001 - a failed re-send is retried at the next step
                a.backend.logerr_throttle(5.0, f'clearance guard: {e}')
            a.backend.sleep(1.0 / C.CONTROL_RATE_HZ)


__all__ = ['ClearanceKeeper', 'VELOCITY_HOLD_AFTER']
