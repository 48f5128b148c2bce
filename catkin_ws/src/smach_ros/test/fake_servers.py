"""Action and service servers used by the smach_ros integration tests (importable or runnable).

TestAction goal codes: g >= 0 succeed after g ms with result g + 1 (cancellable); -1 abort at once;
-2 ignore cancels and succeed after 10 s; -3 run until cancelled (then preempted); -4 run until
cancelled, then report the goal SUCCEEDED (a server that calls a cancelled goal a success).
"""
import sys
import threading
import time

import actionlib
import rospy
from actionlib.msg import TestAction, TestFeedback, TestResult


class FakeActionServer:
    def __init__(self, name):
        self.goals = []
        self.server = actionlib.SimpleActionServer(name, TestAction, execute_cb=self.execute, auto_start=False)
        self.server.start()

    def execute(self, goal):
        g = goal.goal
        self.goals.append(g)
        if g == -1:
            self.server.set_aborted(TestResult(result=-1))
            return
        start = time.monotonic()
        while not rospy.is_shutdown():
            if (g >= 0 and time.monotonic() - start >= g / 1000.0) or (g == -2 and time.monotonic() - start >= 10.0):
                self.server.set_succeeded(TestResult(result=g + 1))
                return
            if self.server.is_preempt_requested() and g == -4:
                self.server.set_succeeded(TestResult(result=-4))
                return
            if self.server.is_preempt_requested() and g != -2:
                self.server.set_preempted(TestResult(result=-3))
                return
            self.server.publish_feedback(TestFeedback(feedback=int((time.monotonic() - start) * 1000)))
            time.sleep(0.01)


class VerdictActionServer:
    """Ends each TestAction goal at once by its code, like the reference server of executive_smach's
    tests: 1 succeeds (empty result), 2 is aborted, 3 is rejected; any other code is left pending."""

    def __init__(self, name):
        self.server = actionlib.ActionServer(name, TestAction, goal_cb=self.on_goal, auto_start=False)
        self.server.start()

    @staticmethod
    def on_goal(handle):
        code = handle.get_goal().goal
        if code == 3:
            handle.set_rejected(None, "rejected by code")
            return
        handle.set_accepted()
        if code == 1:
            handle.set_succeeded(None, "succeeded by code")
        elif code == 2:
            handle.set_aborted(None, "aborted by code")


if __name__ == "__main__":
    # standalone server (the test kills it to check that SimpleActionState notices a dead server)
    rospy.init_node("doomed_server", anonymous=True)
    FakeActionServer(rospy.myargv(sys.argv)[1])
    rospy.spin()
