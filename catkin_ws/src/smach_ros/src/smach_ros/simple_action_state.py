"""SimpleActionState: a state that sends one actionlib goal and maps its result to an outcome."""
from __future__ import annotations

import copy
import threading
import time
import traceback
from typing import Any, Callable, Optional, Sequence

import actionlib
import rospy
from actionlib_msgs.msg import GoalStatus

import smach

__all__ = ["SimpleActionState"]

_POLL_S = 0.02            # how often the waiting loop looks at preempt, timeouts and the server (wall s)
_SERVER_LOST_GRACE_S = 1.0  # the server must be gone this long (wall s) before the goal is given up


class SimpleActionState(smach.State):
    """Sends a goal to an action server and waits for its result.

    Outcomes: ``succeeded``, ``aborted``, ``preempted`` plus ``outcomes``. The goal is ``goal``, or
    ``userdata[goal_key]``, or a default goal filled from ``goal_slots`` keys, then ``goal_cb(ud, goal)``
    may replace or edit it. The result goes to ``userdata[result_key]`` and ``result_slots``, and
    ``result_cb(ud, status, result)`` may choose the outcome.

    .. note:: Differences from upstream, on purpose: the state can run again right after a preemption
       (all per-goal state is local to one ``execute``, and a goal cancelled for a preempt always ends
       as a serviced ``preempted``, whatever status the server gives it); ``exec_timeout`` cancels the
       goal and gives
       ``aborted``; after a cancel, ``preempt_timeout`` bounds the wait for the server; and if the server
       disappears while the goal runs the state returns ``aborted`` instead of hanging.
    """

    def __init__(self, action_name: str, action_spec: Any, goal: Any = None, goal_key: Optional[str] = None,
                 goal_slots: Sequence[str] = (), goal_cb: Optional[Callable] = None,
                 goal_cb_args: Sequence[Any] = (), goal_cb_kwargs: Optional[dict] = None,
                 result_key: Optional[str] = None, result_slots: Sequence[str] = (),
                 result_cb: Optional[Callable] = None, result_cb_args: Sequence[Any] = (),
                 result_cb_kwargs: Optional[dict] = None, input_keys: Sequence[str] = (),
                 output_keys: Sequence[str] = (), outcomes: Sequence[str] = (),
                 exec_timeout: Optional[rospy.Duration] = None,
                 preempt_timeout: Optional[rospy.Duration] = rospy.Duration(60.0),
                 server_wait_timeout: Optional[rospy.Duration] = rospy.Duration(60.0)) -> None:
        smach.State.__init__(self, outcomes=["succeeded", "aborted", "preempted"] + list(outcomes),
                             input_keys=list(input_keys), output_keys=list(output_keys))
        self._action_name = action_name
        self._action_spec = action_spec
        self._exec_timeout = exec_timeout
        self._preempt_timeout = preempt_timeout
        self._server_wait_timeout = server_wait_timeout

        if goal is not None and goal_key is not None:
            raise smach.InvalidStateError("Goal object given to SimpleActionState that takes a goal from userdata.")
        if goal_key is not None and goal_slots:
            raise smach.InvalidStateError("goal_key and goal_slots are mutually exclusive.")
        self._goal = goal if goal is not None else action_spec().action_goal.goal
        self._goal_key = goal_key
        if goal_key is not None:
            self.register_input_keys([goal_key])
        self._goal_slots = list(goal_slots)
        self.register_input_keys(self._goal_slots)
        self._goal_cb = goal_cb
        self._goal_cb_args = list(goal_cb_args)
        self._goal_cb_kwargs = dict(goal_cb_kwargs or {})
        if goal_cb is not None and smach.has_smach_interface(goal_cb):
            self.register_input_keys(goal_cb.get_registered_input_keys())
            self.register_output_keys(goal_cb.get_registered_output_keys())

        if result_key is not None and result_slots:
            raise smach.InvalidStateError("result_key and result_slots are mutually exclusive.")
        self._result_key = result_key
        if result_key is not None:
            self.register_output_keys([result_key])
        self._result_slots = list(result_slots)
        self.register_output_keys(self._result_slots)
        self._result_cb = result_cb
        self._result_cb_args = list(result_cb_args)
        self._result_cb_kwargs = dict(result_cb_kwargs or {})
        if result_cb is not None and smach.has_smach_interface(result_cb):
            self.register_input_keys(result_cb.get_registered_input_keys())
            self.register_output_keys(result_cb.get_registered_output_keys())
            self.register_outcomes(result_cb.get_registered_outcomes())

        self._client = actionlib.SimpleActionClient(action_name, action_spec)

    # ---- helpers --------------------------------------------------------------------------------
    def _server_ready(self) -> bool:
        """True when the action server is fully connected (the check of actionlib's wait_for_server, but
        without blocking, so that it also works while the sim clock is paused)."""
        ac = self._client.action_client
        msg = ac.last_status_msg
        header = getattr(msg, "_connection_header", None) if msg is not None else None
        server_id = header.get("callerid") if header else None
        if server_id is None:
            return False
        if not (ac.pub_goal.impl.has_connection(server_id) and ac.pub_cancel.impl.has_connection(server_id)):
            return False
        subs = (ac.status_sub, ac.result_sub, ac.feedback_sub)
        return all(any(getattr(c, "callerid_pub", None) == server_id for c in sub.impl.connections) for sub in subs)

    def _wait_for_server(self) -> Optional[str]:
        """Wait for the server; returns None when ready, else the outcome to return."""
        start = rospy.get_rostime()
        warned = False
        while not rospy.is_shutdown():
            if self._server_ready():
                return None
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            elapsed = rospy.get_rostime() - start
            if not warned and elapsed > rospy.Duration(2.0):
                rospy.logwarn("Still waiting for action server '%s' to start..." % self._action_name)
                warned = True
            if self._server_wait_timeout is not None and elapsed > self._server_wait_timeout:
                rospy.logerr("Action server for %s is not running (waited %.1f s)."
                             % (self._action_name, self._server_wait_timeout.to_sec()))
                return "aborted"
            time.sleep(_POLL_S)
        return "aborted"

    def _make_goal(self, ud: Any) -> Any:
        if self._goal_key is not None:
            goal = ud[self._goal_key]
        else:
            goal = copy.deepcopy(self._goal)
            for key in self._goal_slots:
                setattr(goal, key, _unwrap(ud[key]))
        if self._goal_cb is not None:
            new_goal = self._goal_cb(ud, goal, *self._goal_cb_args, **self._goal_cb_kwargs)
            if new_goal is not None:
                goal = new_goal
        return _unwrap(goal)

    # ---- execution ------------------------------------------------------------------------------
    def execute(self, ud: Any) -> str:
        if self.preempt_requested():
            rospy.loginfo("Preempting %s before sending goal." % self._action_name)
            self.service_preempt()
            return "preempted"
        early = self._wait_for_server()
        if early is not None:
            return early
        try:
            goal = self._make_goal(ud)
        except Exception:  # noqa: BLE001 - user goal callback
            rospy.logerr("Could not build the goal of action %s: %s" % (self._action_name, traceback.format_exc()))
            return "aborted"

        done = threading.Event()
        box: dict[str, Any] = {}

        def done_cb(status: int, result: Any) -> None:
            box["status"], box["result"] = status, result
            done.set()

        self._client.send_goal(goal, done_cb=done_cb)
        start = rospy.get_rostime()
        cancel_reason: Optional[str] = None
        cancel_time: Optional[rospy.Time] = None
        lost_since: Optional[float] = None
        status: Optional[int] = None
        result: Any = None
        while True:
            if done.wait(_POLL_S):
                status, result = box["status"], box["result"]
                break
            if rospy.is_shutdown():
                self._client.cancel_goal()
                status = GoalStatus.LOST
                break
            now = rospy.get_rostime()
            if cancel_reason is None:
                if self.preempt_requested():
                    rospy.loginfo("Preempting %s: cancelling its goal." % self._action_name)
                    cancel_reason, cancel_time = "preempt", now
                    self._client.cancel_goal()
                elif self._exec_timeout is not None and now - start > self._exec_timeout:
                    rospy.logwarn("Action %s timed out after %.1f s: cancelling its goal."
                                  % (self._action_name, self._exec_timeout.to_sec()))
                    cancel_reason, cancel_time = "timeout", now
                    self._client.cancel_goal()
            elif (self._preempt_timeout is not None and cancel_time is not None
                  and now - cancel_time > self._preempt_timeout):
                rospy.logwarn("Action %s did not end within preempt_timeout (%.1f s) of the cancel: giving up the "
                              "goal." % (self._action_name, self._preempt_timeout.to_sec()))
                status = None
                break
            wall = time.monotonic()
            if self._server_ready():
                lost_since = None
            elif lost_since is None:
                lost_since = wall
            elif wall - lost_since > _SERVER_LOST_GRACE_S:
                rospy.logerr("Action server %s went away while its goal was active: aborting." % self._action_name)
                status = GoalStatus.LOST
                break
        self._client.stop_tracking_goal()
        return self._finish(ud, status, result, cancel_reason)

    def _finish(self, ud: Any, status: Optional[int], result: Any, cancel_reason: Optional[str]) -> str:
        """Store the result and choose the outcome."""
        cb_outcome = None
        if self._result_cb is not None:
            try:
                cb_outcome = self._result_cb(ud, status, result, *self._result_cb_args, **self._result_cb_kwargs)
            except Exception:  # noqa: BLE001 - user callback
                rospy.logerr("Could not execute result callback: " + traceback.format_exc())
                return "aborted"
            if cb_outcome is not None and cb_outcome not in self.get_registered_outcomes():
                rospy.logerr("Result callback for action %s returned '%s' but the only registered outcomes are: %s"
                             % (self._action_name, cb_outcome, self.get_registered_outcomes()))
                return "aborted"
        if result is not None:
            if self._result_key is not None:
                ud[self._result_key] = result
            for key in self._result_slots:
                ud[key] = getattr(result, key)
        if cancel_reason == "preempt":
            # the state cancelled the goal for a preempt: it honours the preempt whatever status the
            # server gave the goal (upstream #52: a server that called it SUCCEEDED left the request
            # set, and the state preempted itself at the start of its next run)
            outcome = "preempted"
        elif status == GoalStatus.SUCCEEDED:
            outcome = "succeeded"
        elif status in (GoalStatus.PREEMPTED, GoalStatus.RECALLED) and self.preempt_requested():
            outcome = "preempted"
        else:
            outcome = "aborted"
        if outcome == "preempted":
            self.service_preempt()
        if cb_outcome is not None:
            outcome = cb_outcome
        return outcome


def _unwrap(value: Any) -> Any:
    """Userdata read through an input-only Remapper may come as a read-only proxy; send the real object."""
    return value._obj if isinstance(value, smach.Const) else value
