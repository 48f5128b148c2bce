#!/usr/bin/env python3
"""End-to-end mission test: waits for the referee to close the short trial and checks its results."""
import json
import os
import time
import unittest

import rospy
import rostest
from std_msgs.msg import Bool

from mbzirc_referee.summary import check_summary


class TestMission(unittest.TestCase):
    def test_short_mission(self):
        timeout = float(rospy.get_param("~timeout", 250.0))
        done = []
        rospy.Subscriber("/mission_recorder/done", Bool, lambda m: done.append(m.data))
        end = time.time() + timeout
        while time.time() < end and not rospy.is_shutdown() and not any(done):
            time.sleep(0.5)
        self.assertTrue(any(done), "the mission recorder never closed the trial")
        out = rospy.get_param("/mission_recorder/output_dir")
        with open(os.path.join(out, "summary.json"), encoding="utf-8") as f:
            s = json.load(f)
        self.assertEqual(check_summary(s), [], f"incomplete summary: {s}")
        self.assertEqual(s["fires_total"], 8, s)
        self.assertGreaterEqual(s["fires_extinguished"], 1, f"no fire went out: {s}")
        # Crashes are measured by bench/bench_mission.py (a target of the mission, not of this test): they
        # come from the agents' manoeuvres and are reported there; here they are only printed.
        print(f"[test_mission] fires out {s['fires_extinguished']}/8, crashes {s['crashes'] or 'none'}")
        self.assertIn(s["end_reason"], ("time", "all_fires_out"), s)
        duration = float(rospy.get_param("/mission_recorder/duration"))
        self.assertTrue(s["end_reason"] == "all_fires_out" or s["sim_time_s"] >= 0.95 * duration, s)
        for f in s["fires"]:
            if f["t_extinguished"] is not None:
                self.assertIsNotNone(f["extinguished_by"], f)
        self.assertGreater(os.path.getsize(os.path.join(out, "report.png")), 10000)


if __name__ == "__main__":
    rospy.init_node("test_mission")
    rostest.rosrun("mbzirc_launchers", "test_mission", TestMission)
