"""A periodic timer on ROS time that survives /clock jumps: use it instead of `rospy.Timer`.

Why: rospy's `Timer` thread dies on `ROSTimeMovedBackwardsException`. One `/clock` message 10 s in the past
(a simulator restarted mid-mission, a bag played with `--clock`, an NTP step of a wall clock) silenced every
periodic output of the system for good (the central unit's tick and heartbeat, the agents' data_feed, the
estimator, the recorder) while the processes stayed alive, so respawn never helped.

Rules of `PeriodicTimer`:
- the callback runs every `period` s of ROS time (sim time when /use_sim_time), from a daemon thread, like
  rospy.Timer, and gets a `rospy.timer.TimerEvent` (only `current_real` / `current_expected` are filled in);
- time moving backwards (during a sleep or a callback): the schedule restarts from the new time
  (next call one period later), and one warning is logged per jump;
- time jumping forwards by more than `JUMP_FACTOR` periods: one call, then the schedule restarts from the
  new time (no burst of missed calls), one warning per jump;
- an exception in the callback is logged (throttled) and the timer goes on: one bad tick must not end
  every later one;
- it ends on ROS shutdown or `shutdown()`.
The clock is injectable (`clock`: `now()`, `sleep(seconds)` raising `TimeMovedBackwards` or
`Interrupted`) so that the rules are unit tested without sleeping.
"""
from __future__ import annotations

import threading
import traceback
from typing import Any, Callable, Optional

JUMP_FACTOR = 5.0          # a forward step of more than this many periods is a jump, not a late tick


class TimeMovedBackwards(Exception):
    """The clock went back while sleeping."""


class Interrupted(Exception):
    """Shutdown while sleeping."""


class RosClock:
    """ROS time through rospy (sim time aware)."""

    def __init__(self) -> None:
        import rospy
        self.rospy = rospy

    def now(self) -> float:
        return self.rospy.get_time()

    def sleep(self, seconds: float) -> None:
        try:
            self.rospy.sleep(max(seconds, 0.0))
        except self.rospy.exceptions.ROSTimeMovedBackwardsException as e:
            raise TimeMovedBackwards(str(e)) from e
        except self.rospy.exceptions.ROSInterruptException as e:
            raise Interrupted(str(e)) from e

    def is_shutdown(self) -> bool:
        return self.rospy.is_shutdown()

    def event(self, expected: float, real: float) -> Any:
        from rospy.timer import TimerEvent
        t = self.rospy.Time.from_sec
        return TimerEvent(None, None, t(max(expected, 0.0)), t(max(real, 0.0)), None)

    def warn(self, text: str) -> None:
        self.rospy.logwarn(text)

    def error(self, text: str) -> None:
        self.rospy.logerr_throttle(10.0, text)


class PeriodicTimer:
    """Calls `callback(event)` every `period` s of ROS time; see the module docstring for the rules.

    Args:
        period: seconds of ROS time (> 0).
        callback: the periodic work.
        name: what the log lines call this timer (e.g. 'central unit tick').
        clock: the time source (default: rospy's).
        start: start the thread now (tests may drive `step()` by hand instead).
    """

    def __init__(self, period: float, callback: Callable[[Any], None], name: str = '',
                 clock: Optional[Any] = None, start: bool = True) -> None:
        if not period > 0.0:
            raise ValueError(f'period must be > 0, not {period}')
        self.period = float(period)
        self.callback = callback
        self.name = name or getattr(callback, '__name__', 'timer')
        self.clock = clock or RosClock()
        self.jumps = 0                      # backward + forward jumps seen (for tests and diagnostics)
        self.errors = 0                     # callback exceptions
        self._stop = threading.Event()
        self._next: Optional[float] = None
        self._thread: Optional[threading.Thread] = None
        if start:
            self._thread = threading.Thread(target=self._run, name=f'periodic:{self.name}', daemon=True)
            self._thread.start()

    def shutdown(self) -> None:
        """Stop after the current sleep (like rospy.Timer.shutdown)."""
        self._stop.set()

    def is_alive(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def _run(self) -> None:
        while not self._stop.is_set() and not self.clock.is_shutdown():
            if not self.step():
                break

    def step(self) -> bool:
        """One sleep and (when due) one call; False when the timer must end (shutdown)."""
        now = self.clock.now()
        if self._next is None:
            if now <= 0.0:          # no /clock yet: wait for it (rospy's sleep does) before scheduling
                try:
                    self.clock.sleep(self.period)
                except TimeMovedBackwards:
                    pass
                except Interrupted:
                    return False
                return True
            self._next = now + self.period
        if now < self._next - self.period - 1e-9:   # went back while we were not sleeping (in the callback)
            self._rescheduled(f'ROS time moved backwards by {self._next - self.period - now:.1f} s', now)
            return True
        try:
            self.clock.sleep(self._next - now)
        except TimeMovedBackwards:
            self._rescheduled('ROS time moved backwards', self.clock.now())
            return True
        except Interrupted:
            return False
        if self._stop.is_set():
            return False
        real = self.clock.now()
        if real < self._next - self.period - 1e-9:
            self._rescheduled(f'ROS time moved backwards by {self._next - self.period - real:.1f} s', real)
            return True
        expected = self._next
        self._fire(expected, real)
        late = real - expected
        if late > JUMP_FACTOR * self.period:
            self._rescheduled(f'ROS time jumped forwards by {late:.1f} s', real, fired=True)
        else:
            self._next = expected + self.period
        return True

    def _fire(self, expected: float, real: float) -> None:
        try:
            self.callback(self.clock.event(expected, real))
        except Exception:   # noqa: BLE001 - one bad tick must not end the timer; logged
            if self.clock.is_shutdown() or self._stop.is_set():
                return          # publishing while rospy shuts down: not an error of the callback
            self.errors += 1
            self.clock.error(f'{self.name}: periodic callback raised (the timer goes on): '
                             f'{traceback.format_exc(limit=6)}')

    def _rescheduled(self, why: str, now: float, fired: bool = False) -> None:
        """Restart the schedule from `now` and log the jump once."""
        self.jumps += 1
        self._next = now + self.period
        self.clock.warn(f'{self.name}: {why}; timer rescheduled from t={now:.1f} s'
                        + (' (missed ticks skipped)' if fired else ''))
