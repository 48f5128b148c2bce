#!/usr/bin/env python3
"""rostest: the ROS scenarios of executive_smach's own rostests (state_machine, sequence, smach_actionlib,
services, monitor), told again here so that CI holds compatibility with programs written for the
original: action states against a server that succeeds / aborts / rejects by goal code, every goal and
result policy of SimpleActionState, ActionServerWrapper, ServiceState and MonitorState.
"""
import threading
import time
import unittest

import actionlib
import rospy
import rostest
import std_srvs.srv
from actionlib.msg import TestAction, TestGoal
from actionlib_msgs.msg import GoalStatus
from std_msgs.msg import Empty

import smach
import smach_ros
from fake_servers import VerdictActionServer

SERVER = "verdict_action"
SUCCEED, ABORT, REJECT = TestGoal(1), TestGoal(2), TestGoal(3)
WAIT = rospy.Duration(10.0)


def action(**kwargs):
    return smach_ros.SimpleActionState(SERVER, TestAction, **kwargs)


class HasKeys(smach.State):
    """'succeeded' if every key is in its userdata, else 'aborted'."""

    def __init__(self, *keys):
        smach.State.__init__(self, outcomes=["succeeded", "aborted"], input_keys=list(keys))
        self.keys = keys

    def execute(self, ud):
        return "succeeded" if all(k in ud for k in self.keys) else "aborted"


class TestActionStatesInContainers(unittest.TestCase):
    def test_add_auto_chain(self):
        sm = smach.StateMachine(["succeeded", "aborted", "preempted", "done"])
        with sm:
            smach.StateMachine.add_auto("FIRST", action(goal=SUCCEED), ["succeeded"])
            smach.StateMachine.add_auto("SECOND", action(goal=SUCCEED), ["succeeded"])
            smach.StateMachine.add("THIRD", action(goal=SUCCEED), {"succeeded": "done"})
        self.assertEqual(sm.execute(), "done")

    def test_sequence(self):
        sq = smach.Sequence(["succeeded", "aborted", "preempted", "done"], connector_outcome="succeeded")
        with sq:
            for label in ("FIRST", "SECOND"):
                smach.Sequence.add(label, action(goal=SUCCEED))
            smach.Sequence.add("THIRD", action(goal=SUCCEED), {"succeeded": "done"})
        self.assertEqual(sq.execute(), "done")

    def test_aborted_and_rejected_goals_give_aborted(self):
        sm = smach.StateMachine(["succeeded", "recovered"])
        with sm:
            to_recovery = {"aborted": "RECOVER", "preempted": "RECOVER"}
            smach.StateMachine.add("OK", action(goal=SUCCEED), dict(to_recovery, succeeded="ABORTED"))
            smach.StateMachine.add("ABORTED", action(goal=ABORT), dict(to_recovery, succeeded="succeeded"))
            smach.StateMachine.add("RECOVER", smach.CBState(lambda ud: "recovered", outcomes=["recovered"]))
        self.assertEqual(sm.execute(), "recovered")
        self.assertEqual(action(goal=REJECT).execute(smach.UserData()), "aborted")

    def test_opened_container_with_instance_add(self):
        sm = smach.StateMachine(["succeeded", "aborted", "preempted"])
        with sm.opened():
            sm.add("FIRST", action(goal=SUCCEED), {})
            sm.add("SECOND", action(goal=ABORT), {})
        self.assertEqual(sm.execute(), "succeeded")  # FIRST's outcome ends the machine

    def test_every_goal_and_result_policy(self):
        sq = smach.Sequence(["succeeded", "aborted", "preempted", "foobar"], "succeeded")
        sq.userdata.g1 = SUCCEED
        sq.userdata.goal = 1
        sq.userdata.goal_alias = 1

        @smach.cb_interface(input_keys=["g1"])
        def goal_from_userdata(ud, default_goal):
            return ud.g1

        goal_policies = [
            ("STATIC", dict(goal=SUCCEED), None),
            ("KEY", dict(goal_key="g1"), None),
            ("SLOTS", dict(goal_slots=["goal"]), None),
            ("SLOTS_REMAPPED", dict(goal_slots=["goal"]), {"goal": "goal_alias"}),
            ("CB", dict(goal_cb=lambda ud, goal: TestGoal(1)), None),
            ("CB_INPUT_KEYS", dict(goal_cb=lambda ud, goal: ud.g1, input_keys=["g1"]), None),
            ("CB_DECORATED", dict(goal_cb=goal_from_userdata), None),
            ("CB_ARGS", dict(goal_cb=lambda ud, goal, g: TestGoal(g), goal_cb_args=[1]), None),
            ("CB_KWARGS", dict(goal_cb=lambda ud, goal, gg: TestGoal(gg), goal_cb_kwargs={"gg": 1}), None),
            ("CB_BOTH", dict(goal_cb=lambda ud, goal, g, gg: TestGoal(g - gg), goal_cb_args=[2],
                             goal_cb_kwargs={"gg": 1}), None),
            # a static goal that would abort, corrected by slots or by a callback editing it in place
            ("STATIC_THEN_SLOTS", dict(goal=ABORT, goal_slots=["goal"]), None),
            ("STATIC_THEN_CB", dict(goal=ABORT, goal_cb=smach.CBInterface(
                lambda ud, goal: setattr(goal, "goal", 1), output_keys=["goal"])), None),
        ]
        with sq:
            for label, kwargs, remapping in goal_policies:
                smach.Sequence.add("GOAL_" + label, action(**kwargs), remapping=remapping)
            smach.Sequence.add("RESULT_KEY", action(goal=SUCCEED, result_key="res_key"))
            smach.Sequence.add("RESULT_KEY_CHECK", HasKeys("res_key"))
            smach.Sequence.add("RESULT_CB", action(goal=SUCCEED, result_cb=smach.CBInterface(
                lambda ud, status, res: setattr(ud, "res_cb", res), output_keys=["res_cb"])))
            smach.Sequence.add("RESULT_CB_CHECK", HasKeys("res_cb"))
            smach.Sequence.add("RESULT_SLOTS", action(goal=SUCCEED, result_slots=["result"]))
            smach.Sequence.add("RESULT_SLOTS_CHECK", HasKeys("result"))
            smach.Sequence.add("RESULT_SLOTS_REMAPPED", action(goal=SUCCEED, result_slots=["result"]),
                               remapping={"result": "res_alias"})
            smach.Sequence.add("RESULT_SLOTS_REMAPPED_CHECK", HasKeys("res_alias"))
            smach.Sequence.add("RESULT_CB_OUTCOME", action(goal=SUCCEED, result_cb=smach.CBInterface(
                lambda ud, status, res: "foobar", outcomes=["foobar"])))
        visited = []
        sq.register_transition_cb(lambda ud, active: visited.extend(active))
        self.assertEqual(sq.execute(), "foobar")
        self.assertEqual(len(visited), len(goal_policies) + 8)  # every state ran, none aborted


class TestActionServerWrapperScenarios(unittest.TestCase):
    def test_goal_slots_expanded_and_result_edited_by_a_callback(self):
        sq = smach.Sequence(["succeeded", "aborted", "preempted"], "succeeded")
        sq.register_input_keys(["goal", "action_goal", "action_result"])
        sq.register_output_keys(["action_result"])

        @smach.cb_interface(input_keys=["action_result"], output_keys=["action_result"])
        def add_one(ud, status, res):
            ud.action_result.result = res.result + 1

        with sq:
            smach.Sequence.add("GOAL_KEY", action(goal_key="action_goal"))
            smach.Sequence.add("GOAL_SLOTS", action(goal_slots=["goal"]))
            smach.Sequence.add("RESULT_CB", action(goal=SUCCEED, result_cb=add_one))
        wrapper = smach_ros.ActionServerWrapper("verdict_sm", TestAction, sq, succeeded_outcomes=["succeeded"],
                                                aborted_outcomes=["aborted"], preempted_outcomes=["preempted"],
                                                expand_goal_slots=True)
        wrapper.run_server()
        client = actionlib.SimpleActionClient("verdict_sm", TestAction)
        self.assertTrue(client.wait_for_server(WAIT))
        self.assertEqual(client.send_goal_and_wait(SUCCEED, WAIT), GoalStatus.SUCCEEDED)
        self.assertEqual(client.get_result().result, 1)

    def test_cancel_preempts_the_wrapped_sequence(self):
        class UntilPreempted(smach.State):
            def __init__(self):
                smach.State.__init__(self, outcomes=["succeeded", "aborted", "preempted"])
                self.started = threading.Event()

            def execute(self, ud):
                self.started.set()
                deadline = time.monotonic() + 10
                while time.monotonic() < deadline:
                    if self.preempt_requested():
                        self.service_preempt()
                        return "preempted"
                    time.sleep(0.02)
                return "succeeded"

        slow = UntilPreempted()
        sq = smach.Sequence(["succeeded", "aborted", "preempted"], "succeeded")
        with sq:
            smach.Sequence.add("PREEMPT_ME", slow)
        smach_ros.ActionServerWrapper("preempt_sm", TestAction, sq, succeeded_outcomes=["succeeded"],
                                      aborted_outcomes=["aborted"], preempted_outcomes=["preempted"]).run_server()
        client = actionlib.SimpleActionClient("preempt_sm", TestAction)
        self.assertTrue(client.wait_for_server(WAIT))
        client.send_goal(SUCCEED)
        self.assertTrue(slow.started.wait(10))
        client.cancel_goal()
        self.assertTrue(client.wait_for_result(WAIT))
        self.assertEqual(client.get_state(), GoalStatus.PREEMPTED)


class TestServiceAndMonitorScenarios(unittest.TestCase):
    def test_service_response_cb_writes_a_remapped_key(self):
        rospy.Service("/empty_upstream", std_srvs.srv.Empty, lambda req: std_srvs.srv.EmptyResponse())

        def response_cb(ud, response):
            ud.foo_var_out = "foo!"
            return "succeeded"

        sm = smach.StateMachine(["succeeded", "aborted", "preempted", "done"])
        with sm:
            smach.StateMachine.add("FOO", smach_ros.ServiceState("/empty_upstream", std_srvs.srv.Empty,
                                                                 response_cb=response_cb,
                                                                 output_keys=["foo_var_out"]),
                                   remapping={"foo_var_out": "sm_var"}, transitions={"succeeded": "done"})
        self.assertEqual(sm.execute(), "done")
        self.assertEqual(sm.userdata.sm_var, "foo!")

    def test_monitor_with_initial_userdata_set_before_it_is_added(self):
        pub = rospy.Publisher("/ping_upstream", Empty, queue_size=1)
        stop = threading.Event()

        def ping():
            while not stop.wait(0.05):
                pub.publish(Empty())

        def copy_b_to_a(ud, msg):
            ud.a = ud.b
            return False

        pinger = threading.Thread(target=ping, daemon=True)
        pinger.start()
        try:
            initial = smach.UserData()
            initial.b = "A"
            sm = smach.StateMachine(["valid", "invalid", "preempted"])
            sm.set_initial_state(["MON"], userdata=initial)
            self.assertEqual(sm.userdata.b, "A")
            with sm:
                smach.StateMachine.add("MON", smach_ros.MonitorState("/ping_upstream", Empty, copy_b_to_a,
                                                                    input_keys=["b"], output_keys=["a"]))
            self.assertEqual(sm.execute(), "invalid")
            self.assertEqual((sm.userdata.a, sm.userdata.b), ("A", "A"))
        finally:
            stop.set()
            pinger.join(2)


def suite():
    loader = unittest.TestLoader()
    return unittest.TestSuite([loader.loadTestsFromTestCase(case) for case in (
        TestActionStatesInContainers, TestActionServerWrapperScenarios, TestServiceAndMonitorScenarios)])


if __name__ == "__main__":
    rospy.init_node("test_upstream_scenarios")
    verdict_server = VerdictActionServer(SERVER)  # one per process: every test case uses it
    rostest.rosrun("smach_ros", "upstream_scenarios", "__main__.suite")
