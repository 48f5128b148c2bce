#!/usr/bin/env python3
"""rostest: the live page in headless Chromium during a short simulated trial.

- the robots wait for the start (the central unit's ~wait_for_start): the page shows "waiting for start",
  no robot gets a task and every UAV stays on the ground; Start trial (confirmed on the page) starts the
  work: the central unit's status says started, robots get tasks, a UAV takes off;
- the robots move on the map as the simulator moves them: each marker, converted back from canvas pixels to
  metres, is within 0.5 m of the simulator's ground truth (/sim/robots, interpolated at the sim time of the
  pose the page shows: at 4x real time a 10 Hz page is up to 0.4 sim seconds behind, 0.6 m at 1.6 m/s);
- the fire list shows the statuses the estimator publishes, and follows them when they change;
- the Home button of a UAV (confirmed on the page) brings it home: it lands within 1.5 m of its home; its
  Release button then makes its agent accept the central unit's goals again (the agent's answer says it was
  held);
- EMERGENCY LAND ALL pauses the central unit and lands every UAV.
"""
import bisect
import json
import math
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import PoseArray
from mbzirc_comm_objs.msg import ObjectList

from page import StationPage

STATUS = {0: "INACTIVE", 1: "ACTIVE", 2: "DETECTED", 3: "LOST", 4: "EXTINGUISHED"}
TOL = 0.5


class Truth:
    """/sim/robots and /estimated_objects as received, by sim time."""

    def __init__(self):
        self.lock = threading.Lock()
        self.robot_t, self.robot_xy, self.last_robots = [], [], None
        self.fire_t, self.fire_status = [], []
        self.ids = [str(i) for i in rospy.get_param("/sim/robot_ids")]
        rospy.Subscriber("/sim/robots", PoseArray, self.on_robots, queue_size=50)
        rospy.Subscriber("/estimated_objects", ObjectList, self.on_fires, queue_size=50)

    def on_robots(self, msg):
        with self.lock:
            self.robot_t.append(msg.header.stamp.to_sec())
            self.robot_xy.append({rid: (p.position.x, p.position.y) for rid, p in zip(self.ids, msg.poses)})
            self.last_robots = [(p.position.x, p.position.y, p.position.z) for p in msg.poses]

    def on_fires(self, msg):
        with self.lock:
            self.fire_t.append(rospy.get_time())
            self.fire_status.append({str(o.id): STATUS[o.status] for o in msg.objects})

    def robots_at(self, t):
        """Ground truth at sim time t, linearly interpolated between the 2 Hz samples (None outside them)."""
        with self.lock:
            i = bisect.bisect_left(self.robot_t, t)
            if i == 0 or i >= len(self.robot_t):
                return None
            t0, t1 = self.robot_t[i - 1], self.robot_t[i]
            a, b = self.robot_xy[i - 1], self.robot_xy[i]
        w = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
        return {r: (a[r][0] + w * (b[r][0] - a[r][0]), a[r][1] + w * (b[r][1] - a[r][1])) for r in a if r in b}

    def fires_between(self, t0, t1):
        """Every estimator message received between t0 and t1, and the last one before t0 (still current
        at t0: the estimator publishes less often while nothing changes)."""
        with self.lock:
            i = bisect.bisect_left(self.fire_t, t0)
            return self.fire_status[max(0, i - 1):bisect.bisect_right(self.fire_t, t1)]


class TestLivePage(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_live_page")
        deadline = time.monotonic() + 60
        port = None
        while port is None or not rospy.has_param("/sim/robot_ids"):
            assert time.monotonic() < deadline, "ground station or simulator did not start"
            port = rospy.get_param("/ground_station/bound_port", None)
            time.sleep(0.2)
        cls.truth = Truth()
        cls.page = StationPage("http://127.0.0.1:%d" % port)
        cls.page.wait_for(lambda s: s["frames"] > 0 and s["robots"], 60, "robots")

    @classmethod
    def tearDownClass(cls):
        cls.page.close()

    def frame_robots(self):
        return json.loads(self.page.eval("JSON.stringify(window.gcs.frame.robots)"))

    def log_text(self):
        return self.page.eval("document.getElementById('log').innerText")

    def test_0_start_trial_starts_the_work(self):
        """Before Start trial nothing moves; the button (confirmed) starts the work."""
        self.page.wait_for(lambda s: "waiting for start" in self.page.eval(
            "document.getElementById('cu').innerText"), 60, "the central unit waiting for the start")
        self.assertEqual(self.page.eval("document.getElementById('start').className"), "waiting")
        t0 = self.page.shown()["t"]
        self.page.wait_for(lambda s: s["t"] > t0 + 5.0, 60, "5 s of sim time while waiting")
        self.assertEqual([r["task"] for r in self.frame_robots() if r["task"]], [], "a task before the start")
        with self.truth.lock:
            self.assertTrue(self.truth.last_robots and all(z < 0.3 for _, _, z in self.truth.last_robots),
                            "a robot left the ground before the start: %s" % self.truth.last_robots)
        self.page.eval("window.confirm = () => true; document.getElementById('start').click(); true")
        self.page.wait_for(lambda s: "start_trial: done" in self.log_text(), 60, "start_trial done in the log")
        self.page.wait_for(lambda s: self.page.eval("window.gcs.frame.cu.started") is True, 30,
                           "the central unit's status: started")
        self.assertNotIn("waiting for start", self.page.eval("document.getElementById('cu').innerText"))
        self.page.wait_for(lambda s: any(r["task"] for r in self.frame_robots()), 60, "a robot given a task")
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            with self.truth.lock:
                if any(z > 1.0 for _, _, z in self.truth.last_robots):
                    break
            time.sleep(0.2)
        else:
            self.fail("no UAV took off after the start")

    def test_1_robots_follow_the_simulator(self):
        compared, worst, start, end = 0, 0.0, None, None
        deadline = time.monotonic() + 40
        while time.monotonic() < deadline and compared < 60:
            shown = self.page.shown()
            time.sleep(0.15)
            for rid, (x, y, stale, stamp) in shown["robots"].items():
                truth = self.truth.robots_at(stamp)
                if truth is None:
                    break
                self.assertIn(rid, truth)
                self.assertFalse(stale, "robot %s shown stale during a running trial" % rid)
                err = math.hypot(x - truth[rid][0], y - truth[rid][1])
                worst = max(worst, err)
                self.assertLess(err, TOL, "robot %s at t=%.2f: page (%.2f, %.2f), simulator (%.2f, %.2f)"
                                % (rid, stamp, x, y, truth[rid][0], truth[rid][1]))
            else:
                compared += 1
                start = start or shown["robots"]
                end = shown["robots"]
        self.assertGreaterEqual(compared, 30, "too few frames compared with the simulator")
        moved = max(math.hypot(end[r][0] - start[r][0], end[r][1] - start[r][1]) for r in start)
        self.assertGreater(moved, 1.0, "no robot moved on the map")
        rospy.loginfo("compared %d frames, worst error %.3f m" % (compared, worst))

    def test_2_fire_statuses_follow_the_estimator(self):
        history = []          # statuses shown, in order
        deadline = time.monotonic() + 180
        while time.monotonic() < deadline:
            shown = self.page.shown()
            if shown["fires"]:
                options = self.truth.fires_between(shown["t"] - 2.0, shown["t"] + 1.0)
                self.assertIn(shown["fires"], options, "page fires at t=%.2f differ from every estimator message "
                              "around then" % shown["t"])
                if not history or history[-1] != shown["fires"]:
                    history.append(shown["fires"])
            changed = [f for f in (history[-1] if history else {})
                       if any(f in h and h[f] != history[-1][f] for h in history)]
            if any(history[-1][f] == "EXTINGUISHED" for f in changed):
                break
            time.sleep(0.2)
        self.assertTrue(history, "no fire shown")
        self.assertTrue(any(f in h and h[f] != history[-1][f] for h in history for f in history[-1]),
                        "no fire status change seen on the page: %s" % history[-3:])

    def test_3_send_home_brings_a_uav_home(self):
        """The Home button of UAV 2 (confirmed): the simulator's UAV 2 lands within 1.5 m of its home."""
        homes = json.loads(self.page.eval("JSON.stringify(window.gcs.info.arena.homes)"))
        home = next(h["home"] for h in homes if h["id"] == "2")
        self.page.eval("window.confirm = () => true; "
                       "document.querySelector('.robot[data-robot=\"2\"] button[data-cmd=send_home]').click(); true")
        self.page.wait_for(lambda s: "send_home UAV 2: done" in self.page.eval(
            "document.getElementById('log').innerText"), 60, "the command done in the log")
        deadline = time.monotonic() + 120
        last = None
        while time.monotonic() < deadline:
            with self.truth.lock:
                i = self.truth.ids.index("2")
                last = self.truth.last_robots[i] if self.truth.last_robots else None
            if last and math.hypot(last[0] - home[0], last[1] - home[1]) < 1.5 and last[2] < 0.3:
                break
            time.sleep(0.5)
        else:
            self.fail("UAV 2 did not land at home %s; last seen at %s" % (home, last))
        # Release (confirmed): the agent accepts goals again; its answer names the hold it had
        self.page.eval("window.confirm = () => true; "
                       "document.querySelector('.robot[data-robot=\"2\"] button[data-cmd=release]').click(); true")
        self.page.wait_for(lambda s: "release UAV 2: done" in self.log_text(), 60, "release done in the log")
        self.assertIn("released (recalled home by the operator)", self.log_text())

    def test_4_emergency_land_all(self):
        """EMERGENCY LAND ALL (confirmed): the central unit pauses and every UAV lands where it is."""
        self.page.eval("window.confirm = () => true; document.querySelector('button[data-cmd=land_all]').click(); true")
        self.page.wait_for(lambda s: "land_all: done" in self.page.eval("document.getElementById('log').innerText"),
                           60, "the command done in the log")
        landed = self.page.wait_for(lambda s: all(r["ual_state"] == "LANDED_DISARMED" for r in json.loads(
            self.page.eval("JSON.stringify(window.gcs.frame.robots)")) if r["kind"] == "uav"), 120,
            "every UAV landed")
        self.assertTrue(landed)
        self.assertIn("PAUSED", self.page.eval("document.getElementById('cu').innerText"))


if __name__ == "__main__":
    rostest.rosrun("mbzirc_ground_station", "live_page", TestLivePage)
