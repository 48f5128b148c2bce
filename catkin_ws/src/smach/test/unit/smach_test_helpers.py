"""Small states used by the tests."""
import threading
import time

import smach


class Const(smach.State):
    """Returns a fixed outcome and records each run."""

    def __init__(self, outcome="done", outcomes=None, **kw):
        smach.State.__init__(self, outcomes=outcomes or [outcome], **kw)
        self.outcome = outcome
        self.runs = 0

    def execute(self, ud):
        self.runs += 1
        return self.outcome


class Waiter(smach.State):
    """Waits until preempted (returns 'preempted' after servicing) or until timeout ('done')."""

    def __init__(self, timeout=5.0, service=True):
        smach.State.__init__(self, outcomes=["done", "preempted"])
        self.timeout = timeout
        self.service = service
        self.started = threading.Event()
        self.saw_preempt_at_start = None

    def execute(self, ud):
        self.saw_preempt_at_start = self.preempt_requested()
        self.started.set()
        t0 = time.monotonic()
        while time.monotonic() - t0 < self.timeout:
            if self.preempt_requested():
                if self.service:
                    self.service_preempt()
                    return "preempted"
                return "done"
            time.sleep(0.005)
        return "done"
