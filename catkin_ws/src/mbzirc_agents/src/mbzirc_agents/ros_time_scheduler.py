"""Two threads per agent that follow ROS time and fire what is due: sleepers' alarms, periodic callbacks.

Why: with /use_sim_time every rospy.Timer, rospy.sleep and actionlib status timer is a thread that rospy
wakes on every /clock message (30 per simulated second, 240 a wall second at 8x real time), and an agent had
more than a dozen of them (one status timer per action server); task sleeps polled the clock every 10 ms of
wall time. Here one thread waits for ROS time updates and sets the event a sleeping task waits on, once
its time has come; another runs the periodic callbacks (so that a callback that blocks never holds a
sleeper beyond its time).

The logic (`fire_alarms`, `run_periodic`) is separate from the threads so that unit tests drive it with a
fake clock.
"""
from __future__ import annotations

import heapq
import itertools
import threading
from typing import Any, Callable, List, Optional, Tuple

#: Wall seconds the thread waits for a ROS time update before it looks again (the clock may be wall time,
#: whose updates notify nobody, or /clock may have stopped).
MAX_WAIT_S = 0.1


class Periodic:
    """A periodic callback on ROS time (what rospy.Timer gives, without a thread of its own)."""

    def __init__(self, period: float, callback: Callable[[Any], None]):
        self.period, self.callback = float(period), callback
        self.next: Optional[float] = None     # first due one period after the scheduler first sees it
        self.stopped = False

    def shutdown(self) -> None:
        """Stop calling back (rospy.Timer's name for it)."""
        self.stopped = True


class RosTimeScheduler:
    """Alarms and periodic callbacks on a clock `now()` whose updates are announced on `time_changed`
    (rospy's rostime condition); `start()` runs them from a daemon thread until `is_shutdown()`."""

    def __init__(self, now: Callable[[], float], time_changed: threading.Condition,
                 is_shutdown: Callable[[], bool], on_error: Callable[[str], None] = lambda _m: None):
        self.now, self.time_changed, self.is_shutdown, self.on_error = now, time_changed, is_shutdown, on_error
        self._lock = threading.Lock()
        self._alarms: List[Tuple[float, int, threading.Event]] = []
        self._periodic: List[Periodic] = []
        self._ids = itertools.count()
        self._last_now: Optional[float] = None
        self._thread: Optional[threading.Thread] = None

    # ---- what the agent asks for ------------------------------------------------------------------
    def alarm(self, at: float) -> threading.Event:
        """An event set once ROS time reaches `at` (or goes back in time: a restarted simulation)."""
        ev = threading.Event()
        with self._lock:
            heapq.heappush(self._alarms, (float(at), next(self._ids), ev))
        self._wake()
        return ev

    def cancel(self, ev: threading.Event) -> None:
        """Forget an alarm nobody waits for any more."""
        with self._lock:
            self._alarms = [a for a in self._alarms if a[2] is not ev]
            heapq.heapify(self._alarms)

    def every(self, period: float, callback: Callable[[Any], None]) -> Periodic:
        """Call `callback(None)` every `period` seconds of ROS time; returns a handle with shutdown()."""
        job = Periodic(period, callback)
        with self._lock:
            self._periodic.append(job)
        self._wake()
        return job

    # ---- the logic ---------------------------------------------------------------------------------
    def fire_due(self, now: float) -> None:
        """Set the alarms and run the callbacks that are due at ROS time `now` (what the two threads do)."""
        self.fire_alarms(now)
        self.run_periodic(now)

    def fire_alarms(self, now: float) -> None:
        """Set the alarms due at ROS time `now` (all of them when time went back)."""
        with self._lock:
            went_back = self._last_now is not None and now < self._last_now
            self._last_now = now
            due = []
            while self._alarms and (went_back or self._alarms[0][0] <= now):
                due.append(heapq.heappop(self._alarms)[2])
        for ev in due:
            ev.set()

    def run_periodic(self, now: float) -> None:
        """Run the periodic callbacks due at ROS time `now`."""
        due = []
        with self._lock:
            self._periodic = [j for j in self._periodic if not j.stopped]
            for job in self._periodic:
                if job.next is None or now < job.next - job.period:     # new, or time went back
                    job.next = now + job.period
                elif now >= job.next:
                    # whole periods: a late tick does not cause a burst of calls
                    job.next += job.period * (int((now - job.next) / job.period) + 1)
                    due.append(job)
        for job in due:
            try:
                job.callback(None)
            except Exception as e:   # a callback's error must not stop every other timer of the agent
                self.on_error(f'periodic callback {getattr(job.callback, "__name__", job.callback)}: {e!r}')

    def next_alarm(self) -> Optional[float]:
        """The earliest ROS time an alarm is due at (None: none)."""
        with self._lock:
            return self._alarms[0][0] if self._alarms else None

    def next_periodic(self) -> Optional[float]:
        """The earliest ROS time a periodic callback is due at (None: none)."""
        with self._lock:
            times = [j.next for j in self._periodic if j.next is not None and not j.stopped]
        return min(times) if times else None

    def next_due(self) -> Optional[float]:
        """The earliest ROS time something is due at (None: nothing scheduled)."""
        times = [t for t in (self.next_alarm(), self.next_periodic()) if t is not None]
        return min(times) if times else None

    # ---- the threads -------------------------------------------------------------------------------
    def start(self) -> "RosTimeScheduler":
        """Two threads: one sets alarms, one runs the periodic callbacks, so that a callback that blocks
        (a publisher, a lock of actionlib) never holds a sleeping task beyond its time."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._loop, args=(self.fire_alarms, self.next_alarm),
                                            name='ros_time_alarms', daemon=True)
            self._thread.start()
            threading.Thread(target=self._loop, args=(self.run_periodic, self.next_periodic),
                             name='ros_time_timers', daemon=True).start()
        return self

    def _wake(self) -> None:
        with self.time_changed:
            self.time_changed.notify_all()

    def _loop(self, fire: Callable[[float], None], next_time: Callable[[], Optional[float]]) -> None:
        while not self.is_shutdown():
            now = self.now()
            fire(now)
            due = next_time()
            # a ROS time update wakes the thread sooner (sim time); on wall time, nothing is announced
            wait = MAX_WAIT_S if due is None else min(MAX_WAIT_S, max(due - now, 0.001))
            with self.time_changed:
                self.time_changed.wait(wait)
        with self._lock:                       # shutdown: nobody sleeps on
            events = [a[2] for a in self._alarms]
            self._alarms = []
        for ev in events:
            ev.set()
