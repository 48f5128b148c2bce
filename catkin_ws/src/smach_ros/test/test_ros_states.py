#!/usr/bin/env python3
"""rostest: ServiceState against real services, MonitorState on a real topic, ConditionState."""
import sys
import threading
import time
import unittest

import rospy
import rostest
from std_msgs.msg import Int32
from std_srvs.srv import SetBool, SetBoolRequest, SetBoolResponse, Trigger

import smach
import smach_ros


def run_async(state, ud=None):
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("o", state.execute(ud or smach.UserData())), daemon=True)
    t.start()
    return t, box


class TestServiceState(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.calls = []

        def set_bool(req):
            cls.calls.append(req.data)
            return SetBoolResponse(success=req.data, message="got %s" % req.data)

        def broken(req):
            raise RuntimeError("service is broken")

        cls.srv = rospy.Service("set_bool", SetBool, set_bool)
        cls.bad = rospy.Service("broken", Trigger, broken)

    def test_request_and_response_key(self):
        st = smach_ros.ServiceState("set_bool", SetBool, request=SetBoolRequest(data=True), response_key="resp")
        ud = smach.UserData()
        r = smach.Remapper(ud, [], ["resp"], {})
        self.assertEqual(st.execute(r), "succeeded")
        self.assertTrue(ud.resp.success)
        self.assertEqual(ud.resp.message, "got True")

    def test_request_slots_and_response_slots(self):
        st = smach_ros.ServiceState("set_bool", SetBool, request_slots=["data"], response_slots=["success", "message"])
        self.assertIn("data", st.get_registered_input_keys())
        ud = smach.UserData()
        ud.data = False
        r = smach.Remapper(ud, ["data"], ["success", "message"], {})
        self.assertEqual(st.execute(r), "succeeded")
        self.assertEqual((ud.success, ud.message), (False, "got False"))

    def test_request_cb_and_response_cb_choose_outcome(self):
        @smach.cb_interface(input_keys=["want"])
        def request_cb(ud, request):
            return SetBoolRequest(data=ud.want)

        @smach.cb_interface(outcomes=["refused"])
        def response_cb(ud, response):
            return None if response.success else "refused"

        st = smach_ros.ServiceState("set_bool", SetBool, request_cb=request_cb, response_cb=response_cb)
        self.assertIn("refused", st.get_registered_outcomes())
        ud = smach.UserData()
        ud.want = False
        self.assertEqual(st.execute(smach.Remapper(ud, ["want"], [], {})), "refused")
        ud.want = True
        self.assertEqual(st.execute(smach.Remapper(ud, ["want"], [], {})), "succeeded")

    def test_failing_service_gives_aborted(self):
        st = smach_ros.ServiceState("broken", Trigger)
        self.assertEqual(st.execute(smach.UserData()), "aborted")

    def test_missing_service_waits_and_is_preemptible(self):
        st = smach_ros.ServiceState("not_there", Trigger)
        t, box = run_async(st)
        time.sleep(0.7)
        self.assertTrue(t.is_alive())
        st.request_preempt()
        t.join(3)
        self.assertEqual(box.get("o"), "preempted")

    def test_service_appearing_later_is_called(self):
        st = smach_ros.ServiceState("late", Trigger, response_key="r")
        ud = smach.UserData()
        t, box = run_async(st, smach.Remapper(ud, [], ["r"], {}))
        time.sleep(0.5)
        srv = rospy.Service("late", Trigger, lambda req: (True, "late but here"))
        try:
            t.join(5)
            self.assertEqual(box.get("o"), "succeeded")
            self.assertEqual(ud.r.message, "late but here")
        finally:
            srv.shutdown()


class TestMonitorState(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.pub = rospy.Publisher("numbers", Int32, queue_size=10)

    def feed(self, values, stop):
        def run():
            i = 0
            while not stop.is_set() and not rospy.is_shutdown():
                self.pub.publish(Int32(values[min(i, len(values) - 1)]))
                i += 1
                time.sleep(0.05)
        t = threading.Thread(target=run, daemon=True)
        t.start()
        return t

    def test_invalid_when_condition_fails(self):
        seen = []

        def cond(ud, msg):
            seen.append(msg.data)
            return msg.data < 3

        st = smach_ros.MonitorState("numbers", Int32, cond)
        stop = threading.Event()
        self.feed([0, 1, 2, 3, 4], stop)
        try:
            self.assertEqual(st.execute(smach.UserData()), "invalid")
        finally:
            stop.set()
        self.assertEqual(seen[-1], 3)

    def test_valid_after_max_checks(self):
        st = smach_ros.MonitorState("numbers", Int32, lambda ud, msg: True, max_checks=3)
        stop = threading.Event()
        self.feed([1], stop)
        try:
            self.assertEqual(st.execute(smach.UserData()), "valid")
        finally:
            stop.set()

    def test_condition_exception_gives_invalid(self):
        st = smach_ros.MonitorState("numbers", Int32, lambda ud, msg: 1 / 0)
        stop = threading.Event()
        self.feed([1], stop)
        try:
            self.assertEqual(st.execute(smach.UserData()), "invalid")
        finally:
            stop.set()

    def test_preempt_and_userdata(self):
        @smach.cb_interface(output_keys=["last"])
        def cond(ud, msg):
            ud.last = msg.data
            return True

        st = smach_ros.MonitorState("numbers", Int32, cond, output_keys=["last"])
        ud = smach.UserData()
        stop = threading.Event()
        self.feed([7], stop)
        try:
            t, box = run_async(st, smach.Remapper(ud, [], ["last"], {}))
            time.sleep(0.5)
            st.request_preempt()
            t.join(3)
        finally:
            stop.set()
        self.assertEqual(box.get("o"), "preempted")
        self.assertEqual(ud.last, 7)
        self.assertFalse(st.preempt_requested())


    def test_67_preempt_whose_wake_up_was_lost_still_ends_it(self):
        # ros/executive_smach#67: a request landing between execute's first check and its clearing of the
        # wake-up event was lost, and the state blocked until the next message (here: none ever comes)
        st = smach_ros.MonitorState("silent_topic", Int32, lambda ud, msg: True)
        t, box = run_async(st, smach.UserData())
        time.sleep(0.3)
        smach.State.request_preempt(st)  # the flag without the wake-up: what the race leaves behind
        t.join(3)
        self.assertEqual(box.get("o"), "preempted")
        self.assertFalse(st.preempt_requested())


class TestConditionState(unittest.TestCase):
    def test_true_false_and_max_checks(self):
        calls = []

        def cond(ud):
            calls.append(1)
            return len(calls) >= 3

        self.assertEqual(smach_ros.ConditionState(cond, max_checks=1).execute(smach.UserData()), "false")
        self.assertEqual(len(calls), 1)
        self.assertEqual(smach_ros.ConditionState(cond, max_checks=5, poll_rate=rospy.Duration(0.01))
                         .execute(smach.UserData()), "true")
        self.assertEqual(len(calls), 3)

    def test_timeout_and_preempt(self):
        st = smach_ros.ConditionState(lambda ud: False, max_checks=-1, timeout=rospy.Duration(0.3),
                                      poll_rate=rospy.Duration(0.01))
        t0 = time.monotonic()
        self.assertEqual(st.execute(smach.UserData()), "false")
        self.assertLess(time.monotonic() - t0, 4.0)
        st2 = smach_ros.ConditionState(lambda ud: False, max_checks=-1)
        t, box = run_async(st2)
        time.sleep(0.2)
        st2.request_preempt()
        t.join(2)
        self.assertEqual(box.get("o"), "preempted")

    def test_input_keys(self):
        st = smach_ros.ConditionState(lambda ud: ud.flag, input_keys=["flag"])
        ud = smach.UserData()
        ud.flag = True
        self.assertEqual(st.execute(smach.Remapper(ud, ["flag"], [], {})), "true")


def suite():
    loader = unittest.TestLoader()
    return unittest.TestSuite([loader.loadTestsFromTestCase(c)
                               for c in (TestServiceState, TestMonitorState, TestConditionState)])


if __name__ == "__main__":
    rospy.init_node("test_ros_states")
    rostest.rosrun("smach_ros", "ros_states", "__main__.suite")
