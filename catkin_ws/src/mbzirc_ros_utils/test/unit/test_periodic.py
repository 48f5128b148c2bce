"""PeriodicTimer: keeps calling through backward and forward /clock jumps, logs each jump once, survives
a callback exception. Driven step by step on a fake clock (no wall-time sleep)."""
import pytest

from mbzirc_ros_utils.periodic import Interrupted, PeriodicTimer, TimeMovedBackwards


class FakeClock:
    """ROS time that advances only when slept on; `jumps` maps a sim time to where the clock jumps when
    a sleep reaches it (a /clock message from a restarted simulator)."""

    def __init__(self, t=100.0):
        self.t = t
        self.jumps = {}
        self.warnings, self.errors = [], []
        self.shutdown = False

    def now(self):
        return self.t

    def sleep(self, seconds):
        if self.shutdown:
            raise Interrupted('shutdown')
        start, target = self.t, self.t + max(seconds, 0.0)
        for at in sorted(self.jumps):
            if start <= at <= target:
                self.t = self.jumps.pop(at)
                if self.t < start:
                    raise TimeMovedBackwards(f'{start - self.t}')
                return
        self.t = target

    def is_shutdown(self):
        return self.shutdown

    def event(self, expected, real):
        return (expected, real)

    def warn(self, text):
        self.warnings.append(text)

    def error(self, text):
        self.errors.append(text)


def run(timer, steps):
    for _ in range(steps):
        if not timer.step():
            break


def test_calls_every_period():
    clock, calls = FakeClock(), []
    timer = PeriodicTimer(0.5, calls.append, 'tick', clock=clock, start=False)
    run(timer, 10)
    assert [round(r, 3) for _, r in calls] == [100.5 + 0.5 * k for k in range(10)]
    assert not clock.warnings


def test_backward_jump_during_sleep_keeps_calling_and_logs_once():
    clock, calls = FakeClock(), []
    clock.jumps[102.2] = 92.0                       # the simulator restarted: 10 s in the past
    timer = PeriodicTimer(0.5, calls.append, 'tick', clock=clock, start=False)
    run(timer, 20)
    after = [r for _, r in calls if r < 100.0]
    assert len(after) >= 10, calls                  # rospy.Timer's thread would have died here
    assert after[0] == pytest.approx(92.5)
    assert len(clock.warnings) == 1 and 'backwards' in clock.warnings[0]
    assert timer.jumps == 1


def test_backward_jump_during_the_callback():
    clock, calls = FakeClock(), []

    def cb(ev):
        calls.append(ev)
        if len(calls) == 3:
            clock.t -= 30.0                         # a bag played with --clock, mid-callback

    timer = PeriodicTimer(1.0, cb, 'tick', clock=clock, start=False)
    run(timer, 10)
    assert len(calls) >= 8 and calls[-1][1] < 100.0
    assert len(clock.warnings) == 1


def test_forward_jump_gives_one_call_then_normal_rate():
    clock, calls = FakeClock(), []
    clock.jumps[101.2] = 500.0
    timer = PeriodicTimer(0.5, calls.append, 'tick', clock=clock, start=False)
    run(timer, 8)
    reals = [r for _, r in calls]
    assert reals.count(500.0) == 1
    assert reals[reals.index(500.0) + 1] == pytest.approx(500.5)     # no burst of missed ticks
    assert len(clock.warnings) == 1 and 'forwards' in clock.warnings[0]


def test_callback_exception_is_logged_and_the_timer_goes_on():
    clock, calls = FakeClock(), []

    def cb(ev):
        calls.append(ev)
        if len(calls) == 2:
            raise RuntimeError('boom')

    timer = PeriodicTimer(0.5, cb, 'tick', clock=clock, start=False)
    run(timer, 6)
    assert len(calls) == 6 and timer.errors == 1 and 'boom' in clock.errors[0]


def test_waits_for_the_first_clock_and_stops_on_shutdown():
    clock, calls = FakeClock(t=0.0), []
    timer = PeriodicTimer(0.5, calls.append, 'tick', clock=clock, start=False)
    assert timer.step() and not calls              # no /clock yet: nothing scheduled from t=0
    clock.t = 1000.0
    run(timer, 3)
    assert len(calls) == 3 and not clock.warnings   # not a "forward jump" from 0 to 1000
    clock.shutdown = True
    assert not timer.step()


def test_bad_period_refused():
    with pytest.raises(ValueError):
        PeriodicTimer(0.0, print, clock=FakeClock(), start=False)
