#!/usr/bin/env python3
"""rostest: IntrospectionServer messages checked field by field, container_init (JSON, safe pickle,
malicious pickle refused) and IntrospectionClient."""
import base64
import os
import pickle
import sys
import threading
import time
import unittest

import rospy
import rostest
from smach_msgs.msg import SmachContainerInitialStatusCmd, SmachContainerStatus, SmachContainerStructure

import smach
import smach_ros
from smach_ros.userdata_codec import decode_local_data

PWNED = "/tmp/smach_introspection_pwned"


class Gate(smach.State):
    """Waits until its event is set."""

    def __init__(self, outcome):
        smach.State.__init__(self, outcomes=[outcome], io_keys=["log"])
        self.event = threading.Event()
        self.outcome = outcome

    def execute(self, ud):
        ud.log = ud.log + [self.outcome]
        self.event.wait(20)
        return self.outcome


class Evil:
    def __reduce__(self):
        return (os.system, ("touch " + PWNED,))


class TestIntrospection(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.a, cls.x = Gate("go"), Gate("sub_done")
        sm = smach.StateMachine(outcomes=["done"])
        sm.userdata.log = []
        sm.userdata.answer = 42
        with sm:
            smach.StateMachine.add("A", cls.a, transitions={"go": "SUB"})
            sub = smach.StateMachine(outcomes=["sub_done"], input_keys=["log"], output_keys=["log"])
            with sub:
                smach.StateMachine.add("X", cls.x)
            smach.StateMachine.add("SUB", sub, transitions={"sub_done": "done"})
        cls.sm, cls.sub = sm, sub
        cls.structures, cls.statuses = {}, []
        cls.lock = threading.Lock()
        cls.server = smach_ros.IntrospectionServer("~intro", sm, "/ROOT")  # '~': private to the node
        cls.server.start()
        ns = rospy.get_name() + "/intro/smach/"
        rospy.Subscriber(ns + "container_structure", SmachContainerStructure, cls.on_structure)
        rospy.Subscriber(ns + "container_status", SmachContainerStatus, cls.on_status)
        cls.init_pub = rospy.Publisher(ns + "container_init", SmachContainerInitialStatusCmd, queue_size=10)

    @classmethod
    def on_structure(cls, msg):
        with cls.lock:
            cls.structures[msg.path] = msg

    @classmethod
    def on_status(cls, msg):
        with cls.lock:
            cls.statuses.append(msg)

    def wait_for(self, pred, timeout=8.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with self.lock:
                for msg in reversed(self.statuses):
                    if pred(msg):
                        return msg
            time.sleep(0.02)
        self.fail("no matching status message")

    def test_1_structure_fields(self):
        deadline = time.monotonic() + 8
        while time.monotonic() < deadline and len(self.structures) < 2:
            time.sleep(0.05)
        root = self.structures["/ROOT"]
        self.assertEqual(list(root.children), ["A", "SUB"])
        edges = set(zip(root.internal_outcomes, root.outcomes_from, root.outcomes_to))
        self.assertEqual(edges, {("go", "A", "SUB"), ("sub_done", "SUB", "done")})
        self.assertEqual(list(root.container_outcomes), ["done"])
        self.assertGreater(root.header.stamp.to_sec(), 0)
        sub = self.structures["/ROOT/SUB"]
        self.assertEqual(list(sub.children), ["X"])
        self.assertEqual(list(zip(sub.internal_outcomes, sub.outcomes_from, sub.outcomes_to)),
                         [("sub_done", "X", "None")])
        self.assertEqual(list(sub.container_outcomes), ["sub_done"])

    def test_2_status_follows_execution(self):
        idle = self.wait_for(lambda m: m.path == "/ROOT" and m.info == "HEARTBEAT")
        self.assertEqual(list(idle.initial_states), ["A"])
        self.assertEqual(list(idle.active_states), [])
        self.assertEqual(decode_local_data(idle.local_data), {"log": [], "answer": 42})
        box = {}
        t = threading.Thread(target=lambda: box.setdefault("o", self.sm.execute()), daemon=True)
        t.start()
        m = self.wait_for(lambda m: m.path == "/ROOT" and list(m.active_states) == ["A"])
        self.assertEqual(m.info, "START")
        self.a.event.set()
        m = self.wait_for(lambda m: m.path == "/ROOT" and list(m.active_states) == ["SUB"])
        self.assertEqual(m.info, "TRANSITION")
        self.assertEqual(decode_local_data(m.local_data)["log"], ["go"])
        m = self.wait_for(lambda m: m.path == "/ROOT/SUB" and list(m.active_states) == ["X"])
        self.assertEqual(decode_local_data(m.local_data)["log"], ["go"])
        self.x.event.set()
        t.join(5)
        self.assertEqual(box.get("o"), "done")
        m = self.wait_for(lambda m: m.path == "/ROOT" and m.info.startswith("TERMINATED"))
        self.assertEqual(m.info, "TERMINATED:done")
        self.assertEqual(list(m.active_states), [])
        self.assertEqual(decode_local_data(m.local_data)["log"], ["go", "sub_done"])

    def send_init(self, path, states, local_data):
        deadline = time.monotonic() + 5
        while self.init_pub.get_num_connections() == 0 and time.monotonic() < deadline:
            time.sleep(0.02)
        self.init_pub.publish(SmachContainerInitialStatusCmd(path=path, initial_states=states, local_data=local_data))

    def test_3_init_with_json(self):
        self.send_init("/ROOT", ["SUB"], '{"answer": 7}')
        self.wait_for(lambda m: m.path == "/ROOT" and m.info == "REMOTE_INIT" and list(m.initial_states) == ["SUB"])
        self.assertEqual(self.sm.get_initial_states(), ["SUB"])
        self.assertEqual(self.sm.userdata.answer, 7)

    def test_4_init_with_plain_pickle(self):
        data = base64.b64encode(pickle.dumps({"answer": 8}, 2)).decode()
        self.send_init("/ROOT", ["A"], data)
        self.wait_for(lambda m: m.path == "/ROOT" and m.info == "REMOTE_INIT" and list(m.initial_states) == ["A"])
        self.assertEqual(self.sm.userdata.answer, 8)

    def test_5_malicious_pickle_refused(self):
        if os.path.exists(PWNED):
            os.remove(PWNED)
        data = base64.b64encode(pickle.dumps({"answer": Evil()}, 2)).decode()
        self.send_init("/ROOT", ["SUB"], data)
        self.send_init("/ROOT", ["NOT_A_STATE"], '{}')
        self.send_init("/NOWHERE", ["A"], '{}')
        time.sleep(1.0)
        self.assertFalse(os.path.exists(PWNED))
        self.assertEqual(self.sm.get_initial_states(), ["A"])
        self.assertEqual(self.sm.userdata.answer, 8)

    def test_6_client(self):
        client = smach_ros.IntrospectionClient()
        server = rospy.get_name() + "/intro"
        self.assertIn(server, client.get_servers())
        ud = smach.UserData()
        ud.answer = 9
        self.assertTrue(client.set_initial_state(server, "/ROOT", ["SUB"], ud, timeout=rospy.Duration(5)))
        self.assertEqual(self.sm.get_initial_states(), ["SUB"])
        self.assertEqual(self.sm.userdata.answer, 9)

    def test_7_stop_unadvertises(self):
        self.server.stop()
        time.sleep(0.5)
        topics = [t for t, _ in rospy.get_published_topics()]
        self.assertNotIn(rospy.get_name() + "/intro/smach/container_status", topics)


if __name__ == "__main__":
    rospy.init_node("test_introspection")
    rostest.rosrun("smach_ros", "introspection", TestIntrospection)
