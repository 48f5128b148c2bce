"""BoundedCall: a service call with a lost link fails fast instead of hanging the agent."""
import threading
import time

import pytest

from mbzirc_agents.bounded_call import BoundedCall, ServiceTimeout


def test_answers_pass_through_and_errors_are_raised_in_the_caller():
    call = BoundedCall('ok', lambda x: x * 2, timeout=1.0)
    assert call(21) == 42
    boom = BoundedCall('boom', lambda: 1 / 0, timeout=1.0)
    with pytest.raises(ZeroDivisionError):
        boom()


def test_a_hanging_service_times_out_and_later_calls_fail_at_once():
    release = threading.Event()
    call = BoundedCall('hang', lambda: release.wait(10), timeout=0.2)
    t0 = time.monotonic()
    with pytest.raises(ServiceTimeout, match='did not answer'):
        call()
    assert time.monotonic() - t0 < 1.0
    t0 = time.monotonic()
    with pytest.raises(ServiceTimeout, match='earlier call'):
        call()                                   # no second thread piles up behind the first
    assert time.monotonic() - t0 < 0.1
    release.set()                                # the link is back: the hung call ends, calls work again
    time.sleep(0.05)
    assert call() is True


def test_other_attributes_of_the_proxy_pass_through():
    class Proxy:
        resolved_name = '/x'

        def __call__(self):
            return 'answer'
    call = BoundedCall('x', Proxy(), timeout=1.0)
    assert call.resolved_name == '/x' and call() == 'answer'
