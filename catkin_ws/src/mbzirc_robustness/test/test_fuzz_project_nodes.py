#!/usr/bin/env python3
"""rostest: fuzz every input of the project's nodes running in this launch; none may die, each must log.

Writes the fuzz report to <repo>/results/robustness/<~report_name> (default fuzz_report.json); the
robustness report merges every fuzz_report*.json there.
"""
import os
import time
import unittest

import rosgraph
import rospkg
import rospy
import rostest

from mbzirc_robustness.fuzz_runner import GraphFuzzer
from mbzirc_robustness.graph import query_pid
from mbzirc_robustness.probes import parse_probes
from mbzirc_robustness.report import format_fuzz_summary, write_json


def repo_root() -> str:
    return os.path.abspath(os.path.join(rospkg.RosPack().get_path("mbzirc_robustness"), "..", "..", ".."))


class TestFuzzProjectNodes(unittest.TestCase):
    data = None

    @classmethod
    def setUpClass(cls):
        rospy.init_node("fuzz_project_nodes")
        wanted = rospy.get_param("~wait_for_nodes", [])
        master = rosgraph.Master(rospy.get_name())
        deadline = time.monotonic() + 40.0
        while time.monotonic() < deadline and any(query_pid(master, n) is None for n in wanted):
            time.sleep(0.5)
        cls.missing = [n for n in wanted if query_pid(master, n) is None]
        time.sleep(1.0)
        fuzzer = GraphFuzzer(max_cases=int(rospy.get_param("~max_cases", 30)),
                             rate_hz=float(rospy.get_param("~rate", 30.0)),
                             seed=int(rospy.get_param("~seed", 0)),
                             exclude_nodes=rospy.get_param("~exclude_nodes", ["/rosout"]),
                             exclude_topics=rospy.get_param("~exclude_topics", ["/clock", "/rosout", "/rosout_agg"]),
                             exclude_cases=rospy.get_param("~exclude_cases", []),
                             probes=parse_probes(rospy.get_param("~probes", [])),
                             fuzz_clock=bool(rospy.get_param("~fuzz_clock", False)))
        cls.data = fuzzer.run().to_dict()
        print(format_fuzz_summary(cls.data), flush=True)
        path = rospy.get_param("~report_path", "") or os.path.join(
            repo_root(), "results", "robustness", rospy.get_param("~report_name", "fuzz_report.json"))
        write_json(path, cls.data)

    def test_every_expected_node_was_fuzzed(self):
        self.assertEqual(self.missing, [], "nodes that never started")
        for n in rospy.get_param("~wait_for_nodes", []):
            self.assertIn(n, self.data["nodes"])
        self.assertGreater(self.data["summary"]["malformed_inputs_tried"], 0)

    def test_no_node_died(self):
        died = self.data["summary"]["nodes_died"]
        self.assertEqual(died, [], "nodes that died, with the input being sent: %s" % died)

    def test_every_probed_node_kept_its_function(self):
        """Alive is not enough: after each batch the node still turns a valid input into a valid output."""
        lost = self.data["summary"]["function_lost"]
        self.assertEqual(lost, [], "nodes alive but no longer doing their job: %s" % lost)
        probed = [p["node"] for p in rospy.get_param("~probes", [])]
        unusable = [s for s in self.data["skipped"] if s["name"].startswith("probe ")]
        self.assertEqual(unusable, [], "probes that failed before any fuzzing (wrong probe?)")
        for n in probed:
            self.assertGreater(self.data["nodes"][n].get("functional_checks", 0), 0, f"{n} never probed")

    def test_every_node_logged_a_clear_error(self):
        silent = self.data["summary"]["silent_nodes"]
        self.assertEqual(silent, [], "nodes that logged no error for any malformed input: %s" % silent)


if __name__ == "__main__":
    rostest.rosrun("mbzirc_robustness", "fuzz_project_nodes", TestFuzzProjectNodes)
