#!/usr/bin/env python3
"""rostest: SimpleActionState against real action servers, and ActionServerWrapper driven by a client."""
import os
import signal
import subprocess
import sys
import threading
import time
import unittest

import actionlib
import rospy
import rostest
from actionlib.msg import TestAction, TestFeedback, TestGoal, TestResult
from actionlib_msgs.msg import GoalStatus

import smach
import smach_ros
from fake_servers import FakeActionServer

HERE = os.path.dirname(os.path.abspath(__file__))
SERVER = "fake_action"


def run_state(state, ud=None):
    sm = smach.StateMachine(outcomes=list(state.get_registered_outcomes()),
                            input_keys=list(state.get_registered_input_keys()),
                            output_keys=list(state.get_registered_output_keys()))
    with sm:
        smach.StateMachine.add("S", state)
    parent = ud if ud is not None else smach.UserData()
    return sm.execute(parent), parent


def run_async(state):
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("o", state.execute(smach.UserData())), daemon=True)
    t.start()
    return t, box


class TestSimpleActionState(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = FakeActionServer(SERVER)
        cls.stubborn = FakeActionServer("stubborn_action")  # busy for 10 s after the ignore-cancel test

    def test_goal_and_result_key(self):
        st = smach_ros.SimpleActionState(SERVER, TestAction, goal=TestGoal(goal=10), result_key="res")
        outcome, ud = run_state(st)
        self.assertEqual(outcome, "succeeded")
        self.assertEqual(ud.res.result, 11)

    def test_goal_slots_result_slots(self):
        st = smach_ros.SimpleActionState(SERVER, TestAction, goal_slots=["goal"], result_slots=["result"])
        self.assertIn("goal", st.get_registered_input_keys())
        ud = smach.UserData()
        ud.goal = 5
        outcome, ud = run_state(st, ud)
        self.assertEqual((outcome, ud.result), ("succeeded", 6))

    def test_goal_key(self):
        st = smach_ros.SimpleActionState(SERVER, TestAction, goal_key="g")
        ud = smach.UserData()
        ud.g = TestGoal(goal=1)
        outcome, ud = run_state(st, ud)
        self.assertEqual(outcome, "succeeded")

    def test_goal_cb_and_result_cb_with_interface(self):
        @smach.cb_interface(input_keys=["base"])
        def goal_cb(ud, goal):
            return TestGoal(goal=ud.base * 2)

        @smach.cb_interface(output_keys=["got"], outcomes=["great"])
        def result_cb(ud, status, result):
            ud.got = result.result
            return "great" if status == GoalStatus.SUCCEEDED else None

        st = smach_ros.SimpleActionState(SERVER, TestAction, goal_cb=goal_cb, result_cb=result_cb)
        self.assertIn("great", st.get_registered_outcomes())
        ud = smach.UserData()
        ud.base = 4
        outcome, ud = run_state(st, ud)
        self.assertEqual((outcome, ud.got), ("great", 9))

    def test_server_abort_gives_aborted(self):
        st = smach_ros.SimpleActionState(SERVER, TestAction, goal=TestGoal(goal=-1))
        self.assertEqual(run_state(st)[0], "aborted")

    def test_preempt_then_reuse(self):
        st = smach_ros.SimpleActionState(SERVER, TestAction, goal=TestGoal(goal=-3))
        t, box = run_async(st)
        time.sleep(0.5)
        st.request_preempt()
        t.join(5)
        self.assertEqual(box.get("o"), "preempted")
        self.assertFalse(st.preempt_requested())
        # reusable right away, twice
        st2_goal = TestGoal(goal=20)
        st._goal = st2_goal
        self.assertEqual(st.execute(smach.UserData()), "succeeded")
        self.assertEqual(st.execute(smach.UserData()), "succeeded")

    def wait_active(self, st):
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and st._client.get_state() != GoalStatus.ACTIVE:
            time.sleep(0.02)
        self.assertEqual(st._client.get_state(), GoalStatus.ACTIVE)

    def test_52_reusable_after_preempt_that_server_reports_as_success(self):
        # ros/executive_smach#52: the server called the cancelled goal SUCCEEDED, the state kept its
        # preempt request, and its next run ended 'preempted' at once without sending a goal
        st = smach_ros.SimpleActionState(SERVER, TestAction, goal=TestGoal(goal=-4), result_key="res")
        t, box = run_async(st)
        self.wait_active(st)
        st.request_preempt()
        t.join(5)
        self.assertEqual(box.get("o"), "preempted")
        self.assertFalse(st.preempt_requested())
        st._goal = TestGoal(goal=20)
        n_goals = len(self.server.goals)
        self.assertEqual(st.execute(smach.UserData()), "succeeded")
        self.assertEqual(self.server.goals[n_goals:], [20])

    def test_88_machine_of_action_states_preempted_twice(self):
        # ros/executive_smach#88: A --preempted--> B --preempted--> C; the second preempt must cancel B's goal
        a = smach_ros.SimpleActionState(SERVER, TestAction, goal=TestGoal(goal=-3))
        b = smach_ros.SimpleActionState(SERVER, TestAction, goal=TestGoal(goal=-3))
        sm = smach.StateMachine(outcomes=["at_c", "at_d", "aborted"])
        with sm:
            smach.StateMachine.add("A", a, transitions={"preempted": "B", "succeeded": "at_d"})
            smach.StateMachine.add("B", b, transitions={"preempted": "C", "succeeded": "at_d"})
            smach.StateMachine.add("C", smach.CBState(lambda ud: "at_c", outcomes=["at_c"]))
        t, box = run_async(sm)
        for state in (a, b):
            self.wait_active(state)
            sm.request_preempt()
        t.join(10)
        self.assertEqual(box.get("o"), "at_c")
        self.assertFalse(sm.preempt_requested())

    def test_preempt_before_execute(self):
        st = smach_ros.SimpleActionState(SERVER, TestAction, goal=TestGoal(goal=20000))
        st.request_preempt()
        t0 = time.monotonic()
        self.assertEqual(st.execute(smach.UserData()), "preempted")
        self.assertLess(time.monotonic() - t0, 5.0)

    def test_exec_timeout_aborts(self):
        st = smach_ros.SimpleActionState(SERVER, TestAction, goal=TestGoal(goal=-3),
                                         exec_timeout=rospy.Duration(0.5))
        t0 = time.monotonic()
        self.assertEqual(st.execute(smach.UserData()), "aborted")
        self.assertLess(time.monotonic() - t0, 8.0)  # the goal itself would never end

    def test_preempt_timeout_bounds_wait_for_ignoring_server(self):
        st = smach_ros.SimpleActionState("stubborn_action", TestAction, goal=TestGoal(goal=-2),
                                         preempt_timeout=rospy.Duration(0.5))
        t, box = run_async(st)
        time.sleep(0.4)
        t0 = time.monotonic()
        st.request_preempt()
        t.join(9)
        self.assertEqual(box.get("o"), "preempted")
        self.assertLess(time.monotonic() - t0, 6.0)  # the server itself would take 10 s

    def test_no_server_gives_aborted_after_server_wait_timeout(self):
        st = smach_ros.SimpleActionState("nobody_home", TestAction, server_wait_timeout=rospy.Duration(0.5))
        t0 = time.monotonic()
        self.assertEqual(st.execute(smach.UserData()), "aborted")
        self.assertLess(time.monotonic() - t0, 5.0)

    def test_server_death_gives_aborted_not_hang(self):
        proc = subprocess.Popen([sys.executable, os.path.join(HERE, "fake_servers.py"), "doomed"])
        try:
            st = smach_ros.SimpleActionState("doomed", TestAction, goal=TestGoal(goal=-3),
                                             server_wait_timeout=rospy.Duration(20))
            t, box = run_async(st)
            deadline = time.monotonic() + 20
            while time.monotonic() < deadline and st._client.get_state() != GoalStatus.ACTIVE:
                time.sleep(0.05)
            self.assertEqual(st._client.get_state(), GoalStatus.ACTIVE)
            proc.send_signal(signal.SIGKILL)
            t.join(10)
            self.assertFalse(t.is_alive(), "SimpleActionState hung after its server died")
            self.assertEqual(box.get("o"), "aborted")
        finally:
            proc.kill()
            proc.wait()


class Countdown(smach.State):
    """Counts to the goal in 10 ms steps, writing feedback and result; preemptible."""

    def __init__(self):
        smach.State.__init__(self, outcomes=["done", "preempted"], input_keys=["action_goal"],
                             output_keys=["action_feedback", "action_result", "result"])

    def execute(self, ud):
        n = ud.action_goal.goal
        for i in range(max(n, 0) if n >= 0 else 10 ** 6):
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            time.sleep(0.01)
        ud.result = n * 10
        return "done"


class TestActionServerWrapper(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        sm = smach.StateMachine(outcomes=["ok", "stopped", "failed"], input_keys=["action_goal"],
                                output_keys=["action_result", "result"])
        with sm:
            smach.StateMachine.add("COUNT", Countdown(), transitions={"done": "FINISH", "preempted": "stopped"})
            smach.StateMachine.add("FINISH", smach.CBState(lambda ud: "ok", outcomes=["ok"]))
        cls.sm = sm
        cls.wrapper = smach_ros.ActionServerWrapper("wrapped", TestAction, sm, succeeded_outcomes=["ok"],
                                                    preempted_outcomes=["stopped"], aborted_outcomes=["failed"],
                                                    result_slots_map={"result": "result"})
        cls.wrapper.run_server()
        cls.client = actionlib.SimpleActionClient("wrapped", TestAction)
        assert cls.client.wait_for_server(rospy.Duration(10))

    def test_goal_succeeds_with_result_slot(self):
        self.client.send_goal(TestGoal(goal=3))
        self.assertTrue(self.client.wait_for_result(rospy.Duration(10)))
        self.assertEqual(self.client.get_state(), GoalStatus.SUCCEEDED)
        self.assertEqual(self.client.get_result().result, 30)

    def test_cancel_preempts_then_next_goal_succeeds(self):
        self.client.send_goal(TestGoal(goal=-1))
        deadline = time.monotonic() + 5
        while not self.sm.is_running() and time.monotonic() < deadline:
            time.sleep(0.02)
        self.assertTrue(self.sm.is_running())
        self.client.cancel_goal()
        self.assertTrue(self.client.wait_for_result(rospy.Duration(10)))
        self.assertEqual(self.client.get_state(), GoalStatus.PREEMPTED)
        self.client.send_goal(TestGoal(goal=2))
        self.assertTrue(self.client.wait_for_result(rospy.Duration(10)))
        self.assertEqual(self.client.get_state(), GoalStatus.SUCCEEDED)
        self.assertEqual(self.client.get_result().result, 20)


class TestWrapperCancelRace(unittest.TestCase):
    """A cancel while the container transitions fast (feedback on every transition) must not deadlock."""

    @classmethod
    def setUpClass(cls):
        class Step(smach.State):
            def __init__(self):
                smach.State.__init__(self, outcomes=["next", "preempted"], output_keys=["action_feedback"])

            def execute(self, ud):
                time.sleep(0.001)
                if self.preempt_requested():
                    self.service_preempt()
                    return "preempted"
                ud.action_feedback = TestFeedback(feedback=int(time.monotonic() * 1000) % 100000)
                return "next"

        sm = smach.StateMachine(outcomes=["preempted", "never"], output_keys=["action_feedback"])
        with sm:
            smach.StateMachine.add("PING", Step(), transitions={"next": "PONG"})
            smach.StateMachine.add("PONG", Step(), transitions={"next": "PING"})
        cls.sm = sm
        cls.feedback = []
        cls.wrapper = smach_ros.ActionServerWrapper("fast_wrapped", TestAction, sm, preempted_outcomes=["preempted"])
        cls.wrapper.run_server()
        cls.client = actionlib.SimpleActionClient("fast_wrapped", TestAction)
        assert cls.client.wait_for_server(rospy.Duration(10))

    def test_cancel_during_fast_transitions(self):
        for _ in range(5):
            self.client.send_goal(TestGoal(goal=0), feedback_cb=lambda fb: self.feedback.append(fb.feedback))
            time.sleep(0.3)
            self.client.cancel_goal()
            self.assertTrue(self.client.wait_for_result(rospy.Duration(10)), "wrapper deadlocked on cancel")
            self.assertEqual(self.client.get_state(), GoalStatus.PREEMPTED)
        self.assertTrue(self.feedback, "no feedback published on transitions")


def suite():
    loader = unittest.TestLoader()
    return unittest.TestSuite([loader.loadTestsFromTestCase(TestSimpleActionState),
                               loader.loadTestsFromTestCase(TestActionServerWrapper),
                               loader.loadTestsFromTestCase(TestWrapperCancelRace)])


if __name__ == "__main__":
    rospy.init_node("test_action_states")
    rostest.rosrun("smach_ros", "action_states", "__main__.suite")
