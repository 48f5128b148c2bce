#!/usr/bin/env python3
"""rostest: FaultSuite's kill -9 check tells a respawned node from a lost one (so its verdicts can fail)."""
import time
import types
import unittest

import rosgraph
import rospy
import rostest

from mbzirc_robustness import faults as F
from mbzirc_robustness.fault_runner import FaultSuite, SuiteConfig
from mbzirc_robustness.graph import query_pid


def suite(recover_wall_s=25.0):
    return FaultSuite(SuiteConfig(recover_wall_s=recover_wall_s, schedule=[F.Fault(F.KIND_CRASH, "x", 0.0)]))


def monitor_stub():
    return types.SimpleNamespace(last_tracks=None, last_tracks_wall=0.0, last_heartbeat_wall=0.0,
                                 last_feed_wall={}, sim_time=lambda: 0.0)


class TestCrashRecovery(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("crash_recovery")
        master = rosgraph.Master("/crash_recovery")
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and any(query_pid(master, n) is None for n in ("/respawner", "/mortal")):
            time.sleep(0.3)

    def test_respawned_node_is_recovered(self):
        f = F.Fault(F.KIND_CRASH, "/respawner", 0.0, check=F.CHECK_PROCESS)
        suite()._crash(f, monitor_stub())
        self.assertTrue(f.result["survived"], f.result)
        self.assertNotEqual(f.result["new_pid"], f.result["old_pid"])

    def test_node_without_respawn_is_lost(self):
        f = F.Fault(F.KIND_CRASH, "/mortal", 0.0, check=F.CHECK_PROCESS)
        suite(10.0)._crash(f, monitor_stub())
        self.assertFalse(f.result["survived"])
        self.assertIn("no new process named /mortal", f.result["detail"])

    def test_respawned_but_silent_is_not_recovered(self):
        f = F.Fault(F.KIND_CRASH, "/respawner", 0.0, check=F.CHECK_HEARTBEAT)  # nobody publishes one
        suite()._crash(f, monitor_stub())
        self.assertFalse(f.result["survived"])
        self.assertIn("did not recover", f.result["detail"])


if __name__ == "__main__":
    rostest.rosrun("mbzirc_robustness", "crash_recovery", TestCrashRecovery)
