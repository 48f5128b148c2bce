"""MonitorState and ConditionState: states that watch a topic or poll a condition."""
from __future__ import annotations

import threading
import traceback
from typing import Any, Callable, Optional, Sequence

import rospy

import smach

__all__ = ["MonitorState", "ConditionState"]


class MonitorState(smach.State):
    """Subscribes to ``topic`` while active and calls ``cond_cb(ud, msg)`` on each message.

    Returns ``invalid`` as soon as ``cond_cb`` returns False (or raises), ``valid`` after ``max_checks``
    messages (never if ``max_checks`` is -1), ``preempted`` when preempted.
    """

    def __init__(self, topic: str, msg_type: Any, cond_cb: Callable, max_checks: int = -1,
                 input_keys: Sequence[str] = (), output_keys: Sequence[str] = ()) -> None:
        smach.State.__init__(self, outcomes=["valid", "invalid", "preempted"], input_keys=list(input_keys),
                             output_keys=list(output_keys))
        self._topic = topic
        self._msg_type = msg_type
        self._cond_cb = cond_cb
        self._max_checks = max_checks
        self._n_checks = 0
        self._invalid = False
        self._trigger_event = threading.Event()
        self._lock = threading.Lock()

    def execute(self, ud: Any) -> str:
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        with self._lock:
            self._n_checks = 0
            self._invalid = False
        self._trigger_event.clear()
        sub = rospy.Subscriber(self._topic, self._msg_type, self._cb, callback_args=ud)
        try:
            while not self._trigger_event.wait(0.1):
                if rospy.is_shutdown():
                    return "preempted"
                if self.preempt_requested():
                    break  # its wake-up was cleared above (upstream #67 blocked until the next message)
        finally:
            sub.unregister()
        if self.preempt_requested():
            self.service_preempt()
            return "preempted"
        with self._lock:
            if self._invalid:
                return "invalid"
        return "valid"

    def _cb(self, msg: Any, ud: Any) -> None:
        with self._lock:
            if self._trigger_event.is_set():
                return  # the state already decided; late messages must not count
            self._n_checks += 1
            try:
                if not self._cond_cb(ud, msg):
                    self._invalid = True
                    self._trigger_event.set()
                    return
            except Exception:  # noqa: BLE001 - user callback
                rospy.logerr("Error thrown while executing condition callback %s: %s"
                             % (self._cond_cb, traceback.format_exc()))
                self._invalid = True
                self._trigger_event.set()
                return
            if self._max_checks > 0 and self._n_checks >= self._max_checks:
                self._trigger_event.set()

    def request_preempt(self) -> None:
        smach.State.request_preempt(self)
        self._trigger_event.set()


class ConditionState(smach.State):
    """Polls ``cond_cb(ud)`` every ``poll_rate``: ``true`` as soon as it holds, ``false`` after
    ``max_checks`` checks (-1: unlimited) or ``timeout``, ``preempted`` when preempted.

    .. note:: It makes exactly ``max_checks`` checks (upstream makes one more).
    """

    def __init__(self, cond_cb: Callable, input_keys: Sequence[str] = (),
                 poll_rate: rospy.Duration = rospy.Duration(0.05), timeout: Optional[rospy.Duration] = None,
                 max_checks: int = 1) -> None:
        smach.State.__init__(self, outcomes=["true", "false", "preempted"], input_keys=list(input_keys))
        self._cond_cb = cond_cb
        self._poll_rate = poll_rate
        self._timeout = timeout
        self._max_checks = max_checks

    def execute(self, ud: Any) -> str:
        start = rospy.get_rostime()
        n_checks = 0
        while not rospy.is_shutdown():
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            try:
                if self._cond_cb(ud):
                    return "true"
            except Exception:  # noqa: BLE001 - user callback
                raise smach.InvalidUserCodeError("Error thrown while executing condition callback %s: %s"
                                                 % (self._cond_cb, traceback.format_exc())) from None
            n_checks += 1
            if self._max_checks != -1 and n_checks >= self._max_checks:
                break
            if self._timeout is not None and rospy.get_rostime() - start > self._timeout:
                break
            try:
                rospy.sleep(self._poll_rate)
            except rospy.ROSInterruptException:
                break
        return "false"
