#!/usr/bin/env python3
"""rostest: the fuzzer finds every input of a node, keeps a robust node alive and catches a fragile one."""
import time
import unittest

import rosgraph
import rospy
import rostest

from mbzirc_robustness.fuzz_runner import GraphFuzzer
from mbzirc_robustness.graph import query_pid
from mbzirc_robustness.report import format_fuzz_summary

ROBUST = "/r1/robust_listener"
FRAGILE = "/fragile_listener"


def wait_up(names, timeout=20.0):
    master = rosgraph.Master("/fuzz_fixtures")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if all(query_pid(master, n) is not None for n in names):
            return True
        time.sleep(0.3)
    return False


class TestFuzzFixtures(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("fuzz_fixtures")
        assert wait_up([ROBUST, FRAGILE]), "fixture nodes never came up"

    def test_1_robust_node_survives_and_logs_errors(self):
        data = GraphFuzzer(target_nodes=[ROBUST], max_cases=25, rate_hz=40).run().to_dict()
        print(format_fuzz_summary(data))
        s = data["summary"]
        names = {i["name"]: i for i in data["inputs"]}
        self.assertIn("/r1/raw_temp_array", names)
        self.assertIn("/r1/rgb_image", names)
        self.assertIn("/r1/trigger", names)
        self.assertEqual(names["/r1/trigger"]["type"], "std_srvs/Trigger")
        self.assertEqual(names["/r1/raw_temp_array"]["connected"], [ROBUST])
        self.assertTrue(s["all_survived"], s["nodes_died"])
        self.assertGreater(s["malformed_inputs_tried"], 40)
        node = data["nodes"][ROBUST]
        self.assertGreater(node["errors_logged"], 0)
        self.assertTrue(any("expected 1024" in e or "bad image" in e for e in node["sample_errors"]))
        self.assertEqual(s["silent_nodes"], [])
        self.assertEqual(s["silent_inputs"], [], "both topics of the robust node log an error")

    def test_2_fragile_node_is_reported_dead_with_the_input(self):
        data = GraphFuzzer(target_nodes=[FRAGILE], max_cases=25, rate_hz=40).run().to_dict()
        print(format_fuzz_summary(data))
        s = data["summary"]
        self.assertFalse(s["all_survived"])
        self.assertEqual([d["node"] for d in s["nodes_died"]], [FRAGILE])
        died_on = s["nodes_died"][0]["died_on"]
        self.assertTrue(died_on.startswith("/pose: "), died_on)
        self.assertIn("nan", died_on.lower(), "the window of cases named must hold the NaN that killed it")
        self.assertIsNone(query_pid(rosgraph.Master("/x"), FRAGILE))


if __name__ == "__main__":
    rostest.rosrun("mbzirc_robustness", "fuzz_fixtures", TestFuzzFixtures)
