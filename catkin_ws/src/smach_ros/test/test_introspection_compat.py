#!/usr/bin/env python3
"""rostest: the introspection behaviours a program ported from executive_smach relies on.

* a relative server name is resolved in the node's namespace (this test node runs in ``/robot_ns``), so
  ``IntrospectionClient`` finds it by that name and can address it with the same relative name;
* ``IntrospectionClient.set_initial_state`` makes a nested machine start in the state it names, with the
  userdata it injects (the scenario of upstream's introspection test, in our words: a root machine whose
  first state would wait forever for a key, and two nested machines; the client moves the start to the
  second one and injects the key);
* a root path of '/' gives children '/<label>';
* userdata that cannot be pickled (a lock, a subprocess, upstream #18/#77) or that is excluded by key does
  not stop the machine nor the status messages;
* with ``allow_init=False`` the server does not listen to container_init at all, and by default it offers
  no debugger (a latched debug status says so, nothing is wrapped, no command subscriber).
"""
import subprocess
import sys
import threading
import time
import unittest

import json

import rosgraph
import rospy
import rostest
from smach_msgs.msg import SmachContainerStatus
from std_msgs.msg import String

import smach
import smach_ros
from smach_ros.userdata_codec import decode_local_data


class WriteKey(smach.State):
    """Writes userdata['key'] = 'written'."""

    def __init__(self):
        smach.State.__init__(self, outcomes=["done"], output_keys=["key"])

    def execute(self, ud):
        ud.key = "written"
        return "done"


class NeedKey(smach.State):
    """Waits (up to 20 s) until userdata holds 'key', then copies it to 'copy'."""

    def __init__(self):
        smach.State.__init__(self, outcomes=["done", "missing"], input_keys=["key"], output_keys=["copy"])

    def execute(self, ud):
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and not rospy.is_shutdown():
            if "key" in ud:
                ud.copy = ud.key
                return "done"
            time.sleep(0.05)
        return "missing"


def nested_writer():
    sm = smach.StateMachine(outcomes=["done"], output_keys=["key"])
    with sm:
        smach.StateMachine.add("WRITE", WriteKey())
    return sm


def wait_until(pred, timeout=20.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        got = pred()
        if got:
            return got
        time.sleep(0.05)
    return pred()


class TestIntrospectionCompat(unittest.TestCase):
    def test_1_relative_name_and_client_initial_state(self):
        root = smach.StateMachine(outcomes=["done", "missing"])
        with root:
            smach.StateMachine.add("WAIT_FIRST", NeedKey(), transitions={"done": "FIRST"})
            smach.StateMachine.add("FIRST", nested_writer(), transitions={"done": "SECOND"})
            smach.StateMachine.add("SECOND", nested_writer(), transitions={"done": "done"})
            smach.StateMachine.add("WAIT_AGAIN", NeedKey(), transitions={"done": "FIRST"})
        server = smach_ros.IntrospectionServer("compat_a", root, "/compat_a")
        starter = threading.Thread(target=server.start)  # as upstream's test does
        starter.start()
        client = smach_ros.IntrospectionClient()
        self.assertEqual(rospy.get_namespace(), "/robot_ns/")
        found = wait_until(lambda: "/robot_ns/compat_a" in client.get_servers())
        self.assertTrue(found, client.get_servers())
        self.assertNotIn(rospy.get_name() + "/compat_a", client.get_servers())  # not private to the node
        injected = smach.UserData()
        injected.key = "injected"
        self.assertTrue(client.set_initial_state("compat_a", "/compat_a", ["SECOND"], injected,
                                                 timeout=rospy.Duration(10.0)))
        self.assertEqual(root.get_initial_states(), ["SECOND"])
        self.assertEqual(root.userdata.key, "injected")
        self.assertEqual(root.execute(), "done")
        self.assertEqual(root.userdata.key, "written")
        server.stop()

    def test_2_root_path_slash(self):
        root = smach.StateMachine(outcomes=["done"])
        with root:
            smach.StateMachine.add("SUB", nested_writer())
        server = smach_ros.IntrospectionServer("compat_b", root, "/")
        paths = set()
        sub = rospy.Subscriber("compat_b/smach/container_status", SmachContainerStatus,
                               lambda m: paths.add(m.path))
        server.start()
        try:
            self.assertTrue(wait_until(lambda: {"/", "/SUB"} <= paths), paths)
            self.assertEqual(paths, {"/", "/SUB"})
        finally:
            sub.unregister()
            server.stop()

    def test_3_unpicklable_and_excluded_userdata(self):
        statuses = []
        lock = threading.Lock()

        class Spawn(smach.State):
            def __init__(self):
                smach.State.__init__(self, outcomes=["done"], output_keys=["process", "lock", "big", "secret"])

            def execute(self, ud):
                process = subprocess.Popen(["true"])
                process.wait()
                ud.process = process
                ud.lock = threading.Lock()
                ud.big = "x" * (300 * 1024)
                ud.secret = "hidden"
                return "done"

        root = smach.StateMachine(outcomes=["done"])
        root.userdata.plain = 5
        with root:
            smach.StateMachine.add("SPAWN", Spawn(), transitions={"done": "AFTER"})
            smach.StateMachine.add("AFTER", nested_writer())
        server = smach_ros.IntrospectionServer("compat_c", root, "/C", exclude_keys=["secret"])

        def on_status(msg):
            with lock:
                statuses.append(msg)
        sub = rospy.Subscriber("compat_c/smach/container_status", SmachContainerStatus, on_status)
        server.start()
        try:
            # connected once a status arrived (get_num_connections can be ahead of the first message)
            self.assertTrue(wait_until(lambda: statuses, 30), "no status from the server")
            self.assertEqual(root.execute(), "done")
            final = wait_until(lambda: [m for m in list(statuses)
                                        if m.path == "/C" and m.info.startswith("TERMINATED")], 20)
            self.assertTrue(final, "no TERMINATED status: the server stopped on unpicklable userdata")
            data = decode_local_data(final[-1].local_data)
            self.assertEqual(data["plain"], 5)
            self.assertTrue(data["process"].startswith("<unpicklable Popen"), data["process"])
            self.assertTrue(data["lock"].startswith("<unpicklable"), data["lock"])
            self.assertIn("cap", data["big"])
            self.assertNotIn("secret", data)
            self.assertEqual(data["key"], "written")
            # the heartbeat goes on too
            n = len(statuses)
            self.assertTrue(wait_until(lambda: any(m.info == "HEARTBEAT" for m in list(statuses)[n:]), 5))
        finally:
            sub.unregister()
            server.stop()

    def test_4_init_can_be_turned_off(self):
        root = smach.StateMachine(outcomes=["done"])
        with root:
            smach.StateMachine.add("A", nested_writer(), transitions={"done": "B"})
            smach.StateMachine.add("B", nested_writer())
        server = smach_ros.IntrospectionServer("compat_d", root, "/D", allow_init=False)
        server.start()
        try:
            client = smach_ros.IntrospectionClient()
            self.assertTrue(wait_until(lambda: "/robot_ns/compat_d" in client.get_servers()))
            topics = [t for t, _ in rospy.get_published_topics()]
            self.assertIn("/robot_ns/compat_d/smach/container_status", topics)
            self.assertFalse(client.set_initial_state("compat_d", "/D", ["B"], timeout=rospy.Duration(1.5)))
            self.assertEqual(root.get_initial_states(), ["A"])
            # the debugger is off by default: a latched status says so, nobody listens to commands
            status = json.loads(rospy.wait_for_message("compat_d/smach/debug/status", String, 5).data)
            self.assertEqual(status["allowed"], False)
            self.assertEqual(status["init_allowed"], False)  # tells viewers not to offer "set initial state"
            self.assertNotIn("execute", root["A"].__dict__)  # nothing wrapped
            master = rosgraph.Master(rospy.get_name())
            subscribed = [t for t, _ in master.getSystemState()[1]]
            self.assertNotIn("/robot_ns/compat_d/smach/debug/command", subscribed)
            self.assertNotIn("/robot_ns/compat_d/smach/container_init", subscribed)
        finally:
            server.stop()


if __name__ == "__main__":
    rospy.init_node("test_introspection_compat")
    rostest.rosrun("smach_ros", "introspection_compat", TestIntrospectionCompat)
