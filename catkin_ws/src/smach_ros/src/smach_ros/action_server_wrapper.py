"""ActionServerWrapper: offers a smach container as an actionlib SimpleActionServer."""
from __future__ import annotations

import copy
import threading
import traceback
from typing import Any, Sequence

import actionlib
import rospy

import smach

__all__ = ["ActionServerWrapper"]


class ActionServerWrapper:
    """Runs ``wrapped_container`` for every goal of the action ``server_name``.

    The goal is put in the container's userdata as ``goal_key`` (and ``goal_slots_map`` {goal_field:
    key}, or every goal field when ``expand_goal_slots``); a default result as ``result_key``. The
    container's outcome decides succeeded / preempted / aborted (any outcome not listed aborts). A cancel
    preempts the container. On every transition, ``userdata[feedback_key]`` (if present, filled through
    ``feedback_slots_map``) is published as feedback. The result comes from ``result_key``,
    ``result_slots_map`` {result_field: key} and, with ``pack_result_slots``, userdata keys named like
    result fields.
    """

    def __init__(self, server_name: str, action_spec: Any, wrapped_container: smach.Container,
                 succeeded_outcomes: Sequence[str] = (), aborted_outcomes: Sequence[str] = (),
                 preempted_outcomes: Sequence[str] = (), goal_key: str = "action_goal",
                 feedback_key: str = "action_feedback", result_key: str = "action_result",
                 goal_slots_map: dict = None, feedback_slots_map: dict = None, result_slots_map: dict = None,
                 expand_goal_slots: bool = False, pack_result_slots: bool = False) -> None:
        self._server_name = server_name
        self._action_spec = action_spec
        self.wrapped_container = wrapped_container
        self._succeeded_outcomes = list(succeeded_outcomes)
        self._aborted_outcomes = list(aborted_outcomes)
        self._preempted_outcomes = list(preempted_outcomes)
        self._goal_key = goal_key
        self._feedback_key = feedback_key
        self._result_key = result_key
        self._goal_slots_map = dict(goal_slots_map or {})
        self._feedback_slots_map = dict(feedback_slots_map or {})
        self._result_slots_map = dict(result_slots_map or {})
        self._expand_goal_slots = expand_goal_slots
        self._pack_result_slots = pack_result_slots
        self._lock = threading.Lock()
        self._action_server = actionlib.SimpleActionServer(server_name, action_spec, execute_cb=self.execute_cb,
                                                           auto_start=False)
        self._action_server.register_preempt_callback(self.preempt_cb)
        wrapped_container.register_transition_cb(self.publish_feedback)

    def run_server(self) -> actionlib.SimpleActionServer:
        """Start accepting goals (returns the SimpleActionServer)."""
        rospy.loginfo("Starting SMACH action server wrapper %s." % self._server_name)
        self._action_server.start()
        return self._action_server

    def publish_feedback(self, userdata: Any, *args: Any) -> None:
        """Transition callback: send ``userdata[feedback_key]`` (with mapped slots) as feedback."""
        if not self._action_server.is_active():
            return
        fb = None
        if self._feedback_key in userdata:
            fb = userdata[self._feedback_key]
        elif self._feedback_slots_map:
            fb = self._action_spec().action_feedback.feedback
        if fb is None:
            return
        try:
            for field, key in self._feedback_slots_map.items():
                if key in userdata:
                    setattr(fb, field, userdata[key])
            self._action_server.publish_feedback(fb)
        except Exception:  # noqa: BLE001 - user data of the wrong type
            rospy.logerr_throttle(1.0, "Could not publish feedback of %s: %s" % (self._server_name, traceback.format_exc()))

    def execute_cb(self, goal: Any) -> None:
        """Run the container for one goal (called by the SimpleActionServer thread)."""
        sc = self.wrapped_container
        if sc.is_running():
            rospy.logwarn("Preempting %s before executing new goal" % self._server_name)
            sc.request_preempt()
            while sc.is_running() and not rospy.is_shutdown():
                rospy.sleep(0.05)
        sc.recall_preempt()  # a preempt that arrived after the last goal ended must not hit this one
        ud = sc.userdata
        ud[self._goal_key] = goal
        for field, key in self._goal_slots_map.items():
            ud[key] = getattr(goal, field)
        if self._expand_goal_slots:
            for field in goal.__slots__:
                ud[field] = getattr(goal, field)
        ud[self._result_key] = self._action_spec().action_result.result
        if self._action_server.is_preempt_requested():
            sc.request_preempt()  # (this thread holds no actionlib lock here)
        try:
            outcome = sc.execute(ud)
        except Exception:  # noqa: BLE001 - keep serving goals after a broken run
            rospy.logerr("Exception in the SMACH container of %s: %s" % (self._server_name, traceback.format_exc()))
            if self._action_server.is_active():
                self._action_server.set_aborted(text="container raised an exception")
            return
        result = ud[self._result_key] if self._result_key in ud else self._action_spec().action_result.result
        result = copy.copy(result._obj if isinstance(result, smach.Const) else result)
        try:
            for field, key in self._result_slots_map.items():
                if key in ud:
                    setattr(result, field, ud[key])
            if self._pack_result_slots:
                for field in result.__slots__:
                    if field in ud:
                        setattr(result, field, ud[field])
        except Exception:  # noqa: BLE001
            rospy.logerr("Could not fill the result of %s: %s" % (self._server_name, traceback.format_exc()))
        if not self._action_server.is_active():
            return
        if outcome in self._succeeded_outcomes:
            rospy.loginfo("SUCCEEDED: %s" % outcome)
            self._action_server.set_succeeded(result, "SMACH outcome: %s" % outcome)
        elif outcome in self._preempted_outcomes:
            rospy.loginfo("PREEMPTED: %s" % outcome)
            self._action_server.set_preempted(result, "SMACH outcome: %s" % outcome)
        else:
            if outcome not in self._aborted_outcomes:
                rospy.logwarn("Outcome '%s' of %s is not listed in any outcome list: aborting." % (outcome, self._server_name))
            rospy.loginfo("ABORTED: %s" % outcome)
            self._action_server.set_aborted(result, "SMACH outcome: %s" % outcome)

    def preempt_cb(self) -> None:
        """A cancel (or a newer goal) arrived: preempt the running container.

        .. note:: actionlib calls this with its own locks held, and the container's transition
           callbacks (feedback) need those locks while the container holds its transition lock; so the
           preempt request is made from another thread, never from here (that would deadlock).
        """
        if self.wrapped_container.is_running():
            rospy.logdebug("Preempt on action server wrapper %s" % self._server_name)
            threading.Thread(target=self.wrapped_container.request_preempt, name="smach_wrapper_preempt",
                             daemon=True).start()
