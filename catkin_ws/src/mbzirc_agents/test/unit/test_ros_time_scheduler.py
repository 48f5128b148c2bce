"""RosTimeScheduler: alarms and periodic callbacks on ROS time, driven here by hand (no thread, no sleep)."""
import threading

from mbzirc_agents.ros_time_scheduler import RosTimeScheduler


def make():
    errors = []
    return RosTimeScheduler(lambda: 0.0, threading.Condition(), lambda: False, errors.append), errors


def test_alarm_set_when_ros_time_reaches_it():
    s, _ = make()
    ev = s.alarm(10.0)
    s.fire_due(9.9)
    assert not ev.is_set()
    s.fire_due(10.0)
    assert ev.is_set()


def test_alarms_fire_in_time_order_and_only_when_due():
    s, _ = make()
    late, early = s.alarm(5.0), s.alarm(2.0)
    s.fire_due(3.0)
    assert early.is_set() and not late.is_set()
    assert s.next_due() == 5.0


def test_time_going_back_wakes_every_sleeper():
    """A restarted simulation (or a bag loop) must not leave a task asleep until the old time returns."""
    s, _ = make()
    s.fire_due(100.0)
    ev = s.alarm(150.0)
    s.fire_due(1.0)
    assert ev.is_set()


def test_cancelled_alarm_is_forgotten():
    s, _ = make()
    ev = s.alarm(1.0)
    s.cancel(ev)
    assert s.next_due() is None
    s.fire_due(2.0)
    assert not ev.is_set()


def test_periodic_runs_once_per_period_without_bursts():
    s, _ = make()
    calls = []
    s.every(0.1, calls.append)
    t = 0.0
    for _ in range(91):                  # 3 s of 30 Hz clock ticks
        s.fire_due(t)
        t += 1.0 / 30.0
    assert 28 <= len(calls) <= 30
    n = len(calls)
    s.fire_due(t + 5.0)                  # a 5 s stall: one call, not fifty
    assert len(calls) == n + 1


def test_shutdown_periodic_stops():
    s, _ = make()
    calls = []
    job = s.every(1.0, calls.append)
    s.fire_due(0.0)
    s.fire_due(1.0)
    job.shutdown()
    s.fire_due(2.0)
    assert len(calls) == 1


def test_a_failing_callback_does_not_stop_the_others():
    s, errors = make()
    calls = []

    def bad(_event):
        raise RuntimeError("boom")
    s.every(1.0, bad)
    s.every(1.0, calls.append)
    s.fire_due(0.0)
    s.fire_due(1.0)
    assert calls == [None] and errors and "boom" in errors[0]
