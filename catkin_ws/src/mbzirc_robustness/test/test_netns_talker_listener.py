#!/usr/bin/env python3
"""rostest: ROS across network-namespace hosts works, a cut link stops traffic, a restored one resumes it,
and every namespace and process of the lab is gone afterwards."""
import subprocess
import unittest

import rostest

from mbzirc_robustness import constants as C
from mbzirc_robustness.netns import NetnsLab, install_signal_cleanup
from mbzirc_robustness.netns_demo import talker_listener


class TestNetnsTalkerListener(unittest.TestCase):
    def test_traffic_across_hosts_and_link_cut(self):
        lab = NetnsLab()
        install_signal_cleanup(lab)
        with lab:
            for h in (C.GROUND_STATION, "uav1", "uav2"):
                lab.add_host(h)
            res = talker_listener(lab, cut_s=4.0)
            names = [h.ns for h in lab.hosts.values()] + [lab.sw]
            procs = [p for h in lab.hosts.values() for p in h.procs]
        print(res)
        self.assertEqual(res.problems, [])
        self.assertGreaterEqual(res.before_cut, 5)
        self.assertEqual(res.during_cut, 0)
        self.assertGreaterEqual(res.after_restore, 5)
        listed = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
        self.assertFalse([n for n in names if n in listed], "namespaces left behind")
        self.assertTrue(all(p.poll() is not None for p in procs), "processes left behind")


if __name__ == "__main__":
    rostest.rosrun("mbzirc_robustness", "netns_talker_listener", TestNetnsTalkerListener)
