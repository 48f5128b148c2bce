#!/usr/bin/env python3
"""rostest: `replay` of the committed short bag shows, at each time t, the robots where the bag's data_feeds
put them at t (what the live page showed), scrubbing back and forth and while playing; `replay` without a
bag offers the recordings of its results directory: the one picked on the page is replayed the same way,
and a name outside the directory or of a file that is no bag is refused with the reason on the page."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import unittest
import urllib.request

import rosbag
import rospkg
import rostest

from page import StationPage

PKG = rospkg.RosPack().get_path("mbzirc_ground_station")
BAG = os.path.join(PKG, "test", "data", "short_mission.bag")
TOL = 0.05   # m: the page's canvas pixels converted back to metres (float pixels, no rounding)


def feeds_at(t):
    """Each robot's last data_feed pose at or before bag time t."""
    out = {}
    with rosbag.Bag(BAG) as bag:
        for topic, msg, mt in bag.read_messages():
            if mt.to_sec() > t:
                break
            if topic.endswith("/data_feed") and msg.pose.header.frame_id:
                p = msg.pose.pose.position
                out[topic.split("/")[1].split("_")[1]] = (p.x, p.y)
    return out


class TestReplayPage(unittest.TestCase):
    @staticmethod
    def launch_replay(port, *args):
        """Start the replay node on port (0: any) with args; returns (process, the port it bound)."""
        port_file = os.path.join(tempfile.mkdtemp(prefix="gcs_replay_"), "port")
        proc = subprocess.Popen([sys.executable, os.path.join(PKG, "scripts", "replay"), *args, "--port",
                                 str(port), "--port-file", port_file])
        deadline = time.monotonic() + 30
        while not os.path.exists(port_file) or not open(port_file).read():
            if time.monotonic() > deadline or proc.poll() is not None:
                proc.kill()
                raise AssertionError("replay did not start")
            time.sleep(0.1)
        return proc, int(open(port_file).read())

    @classmethod
    def start_replay(cls, port):
        cls.proc, port = cls.launch_replay(port, BAG)
        return port

    @classmethod
    def setUpClass(cls):
        cls.port = cls.start_replay(0)
        cls.base = "http://127.0.0.1:%d" % cls.port
        with rosbag.Bag(BAG) as bag:
            cls.start, cls.end = bag.get_start_time(), bag.get_end_time()
        try:
            cls.page = StationPage(cls.base)
            cls.page.wait_for(lambda s: s["replay"] is not None, 30, "the replay timeline")
        except BaseException:
            cls.proc.terminate()   # tearDownClass does not run after a failed setUpClass
            cls.proc.wait(10)
            raise

    @classmethod
    def tearDownClass(cls):
        cls.page.close()
        cls.proc.terminate()
        cls.proc.wait(10)

    def control(self, body, base=None):
        req = urllib.request.Request((base or self.base) + "/api/replay", json.dumps(body).encode(),
                                     {"Content-Type": "application/json"})
        with urllib.request.urlopen(req, timeout=30) as r:   # generous: the suite runs on a busy machine
            self.assertEqual(json.load(r), {"ok": True})

    def check_positions(self, shown):
        t = shown["replay"]["t"]
        truth = feeds_at(t)
        self.assertTrue(truth, "no data_feed before %.2f" % t)
        self.assertEqual(sorted(shown["robots"]), sorted(truth))
        for rid, (x, y) in truth.items():
            px, py = shown["robots"][rid][:2]
            self.assertLess(abs(px - x) + abs(py - y), TOL, "robot %s at t=%.2f: page (%.2f, %.2f), bag (%.2f, %.2f)"
                            % (rid, t, px, py, x, y))

    def test_scrub_shows_the_recorded_positions(self):
        for dt in (20.0, 5.0, 29.0, 12.5, 12.4):
            target = round(self.start + dt, 2)
            self.control({"action": "seek", "t": target})
            shown = self.page.wait_for(lambda s: s["replay"] and abs(s["replay"]["t"] - target) < 1e-6, 30,
                                       "t = %.2f" % target)
            self.check_positions(shown)

    def test_play_moves_the_robots_as_recorded(self):
        self.control({"action": "seek", "t": self.start + 1.0})
        self.control({"action": "speed", "speed": 4.0})
        self.control({"action": "play"})
        seen = []
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and len(seen) < 15:
            shown = self.page.shown()
            if shown["replay"]["playing"] and shown["replay"]["t"] not in [s["replay"]["t"] for s in seen]:
                seen.append(shown)
            time.sleep(0.15)
        self.control({"action": "pause"})
        self.assertGreaterEqual(len(seen), 10, "the timeline did not advance while playing")
        for shown in seen:
            self.check_positions(shown)
        moved = max(abs(seen[-1]["robots"][r][0] - seen[0]["robots"][r][0]) +
                    abs(seen[-1]["robots"][r][1] - seen[0]["robots"][r][1]) for r in seen[0]["robots"])
        self.assertGreater(moved, 1.0, "no robot moved on the page while playing")

    def test_z_page_reconnects_after_a_restart(self):
        """The replay node stops and comes back on the same port: the page shows it and carries on."""
        self.proc.terminate()
        self.proc.wait(10)
        self.page.wait_for(lambda s: s["conn"] != "connected", 30, "the connection lost")
        self.start_replay(self.port)
        before = self.page.shown()["frames"]
        self.page.wait_for(lambda s: s["conn"] == "connected" and s["frames"] > before + 5, 60,
                           "frames again after the restart")
        self.control({"action": "seek", "t": self.start + 7.0})
        self.check_positions(self.page.wait_for(
            lambda s: s["replay"] and abs(s["replay"]["t"] - (self.start + 7.0)) < 1e-6, 30, "the seek"))

    def test_zz_picked_recording_is_replayed(self):
        """`replay` without a bag: the page lists the results directory's bags; the one picked plays."""
        results = tempfile.mkdtemp(prefix="gcs_results_")
        os.makedirs(os.path.join(results, "trial_a"))
        shutil.copy(BAG, os.path.join(results, "trial_a", "mission.bag"))
        with open(os.path.join(results, "notes.txt"), "w") as f:
            f.write("not a bag")
        proc, port = self.launch_replay(0, "--results-dir", results)
        base = "http://127.0.0.1:%d" % port
        try:
            self.page.eval("location.assign(%s); true" % json.dumps(base + "/"))
            self.page.wait_for(lambda s: self.page.eval(
                "Array.from(document.querySelectorAll('#recordings option')).map((o) => o.value).join(',')")
                == ",trial_a/mission.bag", 30, "the picker listing the one bag")
            self.assertIn("pick one", self.page.eval("document.getElementById('mode').textContent"))
            self.page.eval("const s = document.getElementById('recordings'); s.value = 'trial_a/mission.bag'; "
                           "s.dispatchEvent(new Event('change')); true")
            self.page.wait_for(lambda s: s["replay"] is not None, 30, "the picked recording's timeline")
            self.assertEqual(self.page.eval("location.search"), "?bag=trial_a%2Fmission.bag")
            self.assertIn("REPLAY of trial_a/mission.bag", self.page.eval("document.getElementById('mode').textContent"))
            for dt in (6.0, 21.5):
                target = round(self.start + dt, 2)
                self.control({"bag": "trial_a/mission.bag", "action": "seek", "t": target}, base)
                self.check_positions(self.page.wait_for(
                    lambda s: s["replay"] and abs(s["replay"]["t"] - target) < 1e-6, 30, "t = %.2f" % target))
            for name, why in (("../trial_a/mission.bag", "'..' is refused"), ("notes.txt", "is not a bag"),
                              ("/etc/passwd", "absolute paths are refused")):
                self.page.eval("location.assign(%s); true" % json.dumps(base + "/?bag=" + name))
                self.page.wait_for(lambda s: why in self.page.eval(
                    "document.getElementById('pickerror').textContent"), 30, "the refusal of %s" % name)
        finally:
            proc.terminate()
            proc.wait(10)


if __name__ == "__main__":
    rostest.rosrun("mbzirc_ground_station", "replay_page", TestReplayPage)
