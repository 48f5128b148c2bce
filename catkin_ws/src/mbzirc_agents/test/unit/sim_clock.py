"""A simulated clock for the agents' unit tests: time advances only when every thread that uses the clock
waits on it, straight to the earliest wake-up, so a test of 60 s of robot time runs in well under a second.

Why: the agent is threaded (state machine, action servers, heartbeat watchdog) and its tasks sleep and
poll on the backend's clock; on a wall clock the tests waited for real (about 3 minutes). Rules:
- the thread that makes the clock takes part, a thread started with `start_thread` (the backend's
  `start_thread`) from its start, and any other thread once it calls `sleep` or `wait`; time does not move
  while any such thread runs (a participant that blocks on anything else, e.g. a bare `time.sleep`, stalls
  the clock: use this one);
- `wait(event, timeout)` returns as soon as the event is set (checked before time moves on);
- `stop()` (the backend's shutdown) wakes everybody; later calls return at once, after a 1 ms wall yield
  so that a stray loop left behind by a failed test cannot spin a core.
"""
import threading
import time

WALL_POLL = 0.05     # s: how often a waiting thread looks again for an event set by a thread outside the clock


class SimClock:
    def __init__(self, start=1000.0):
        self._t = float(start)
        self._cv = threading.Condition()
        # threading.Thread objects that sleep / wait on this clock; the one that makes the clock (the test)
        # from the start, so that time stands still while it sets the scene up
        self._participants = {threading.current_thread()}
        self._waiting = {}              # thread -> (deadline or None, event or None)
        self._stopped = False

    def start_thread(self, target, *args, name=None):
        """Start a daemon thread that takes part from the start: time waits for it until it first waits
        (a thread that joined only at its first wait could find seconds gone, e.g. an action server's
        thread by the time it hands the goal over)."""
        t = threading.Thread(target=target, args=args, name=name, daemon=True)
        with self._cv:
            self._participants.add(t)
        t.start()
        return t

    def now(self):
        """Simulated seconds."""
        with self._cv:
            return self._t

    def stop(self):
        with self._cv:
            self._stopped = True
            self._cv.notify_all()

    def sleep(self, seconds):
        """Sleep `seconds` of simulated time."""
        self._block(max(0.0, float(seconds)), None)

    def wait(self, event, timeout=None):
        """threading.Event.wait on simulated time: True when the event is set."""
        return self._block(None if timeout is None else max(0.0, float(timeout)), event)

    def _block(self, duration, event):
        me = threading.current_thread()
        with self._cv:
            if self._stopped:
                stopped = True
            else:
                stopped = False
                deadline = None if duration is None else self._t + duration
                self._participants.add(me)
                self._waiting[me] = (deadline, event)
                try:
                    while True:
                        if event is not None and event.is_set():
                            return True
                        if deadline is not None and self._t >= deadline:
                            return False
                        if self._stopped:
                            break
                        self._advance_if_all_wait()
                        if (event is not None and event.is_set()) or (deadline is not None and self._t >= deadline):
                            continue
                        self._cv.wait(WALL_POLL)
                finally:
                    del self._waiting[me]
                stopped = True
        if stopped:
            time.sleep(0.001)
        return event is not None and event.is_set()

    def _advance_if_all_wait(self):
        """Called with the lock held: when every live participant waits and none can go on, move time
        to the earliest deadline and wake everybody."""
        # a thread not started yet (ident None) is about to run: it counts as running
        self._participants = {t for t in self._participants if t.ident is None or t.is_alive()}
        if any(t not in self._waiting for t in self._participants):
            return
        deadlines = []
        for deadline, event in self._waiting.values():
            if (event is not None and event.is_set()) or (deadline is not None and deadline <= self._t):
                self._cv.notify_all()
                return
            if deadline is not None:
                deadlines.append(deadline)
        if deadlines:
            self._t = min(deadlines)
            self._cv.notify_all()
