#!/usr/bin/env python3
"""rostest: the web viewer page in headless Chromium follows a running machine (smach_demo).

Checks that the highlighted state in the browser changes as the machine runs, and only to states the
machine really entered (cross-checked with the status topic), that nested containers highlight, that the
userdata panel shows the machine's userdata, that "Set as initial state" reaches the machine, and that the
page loads nothing from outside the viewer.
"""
import json
import sys
import threading
import time
import unittest
import urllib.request

import rospy
import rostest
from smach_msgs.msg import SmachContainerStatus

from cdp import HeadlessChromium

SERVER = "/smach_demo/demo"
ACTIVE_JS = "JSON.stringify(Array.from(document.querySelectorAll('#graph g.active')).map(e => e.id))"


class TestWebViewer(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.truth = set()       # ids of states the machine really had active
        cls.initials = []
        cls.lock = threading.Lock()
        rospy.Subscriber(SERVER + "/smach/container_status", SmachContainerStatus, cls.on_status, queue_size=100)
        deadline = time.monotonic() + 30
        port = None
        while time.monotonic() < deadline and port is None:
            port = rospy.get_param("/smach_web_viewer/bound_port", None)
            time.sleep(0.1)
        assert port, "web viewer did not start"
        cls.base = "http://127.0.0.1:%d" % port
        while time.monotonic() < deadline:  # wait until the viewer has discovered the demo's structure
            try:
                with urllib.request.urlopen(cls.base + "/api/state", timeout=2) as r:
                    snap = json.load(r)
                root = snap["servers"].get(SERVER, {}).get("containers", {}).get("/ROOT")
                if root and root["has_structure"]:
                    break
            except OSError:
                pass
            time.sleep(0.2)
        cls.browser = HeadlessChromium()
        cls.browser.open(cls.base + "/")

    @classmethod
    def tearDownClass(cls):
        cls.browser.close()

    @classmethod
    def on_status(cls, msg):
        with cls.lock:
            for label in msg.active_states:
                cls.truth.add("s:%s/%s" % (msg.path, label))
                cls.truth.add("c:%s/%s" % (msg.path, label))
            if msg.path == "/ROOT":
                cls.initials.append(list(msg.initial_states))

    def poll(self, predicate, timeout=20.0, period=0.1):
        deadline = time.monotonic() + timeout
        last = None
        while time.monotonic() < deadline:
            last = predicate()
            if last:
                return last
            time.sleep(period)
        return last

    def test_1_highlight_follows_machine(self):
        seen = []
        top = set()

        def sample():
            ids = json.loads(self.browser.eval(ACTIVE_JS) or "[]")
            if ids and (not seen or seen[-1] != ids):
                seen.append(ids)
            for i in ids:
                if i.startswith("s:/ROOT/") and i.count("/") == 2 or i.startswith("c:/ROOT/") and i.count("/") == 2:
                    top.add(i.split(":", 1)[1])
            return len(top) >= 3 and any("s:/ROOT/SCAN/" in i for ids_ in seen for i in ids_)

        ok = self.poll(sample, timeout=30)
        self.assertTrue(ok, "highlight did not follow the machine; saw %s" % seen)
        self.assertGreaterEqual(len(seen), 3)
        with self.lock:
            truth = set(self.truth)
        for ids in seen:
            for i in ids:
                self.assertIn(i, truth, "page highlighted %s which the machine never had active" % i)
        # the nested machine's cluster is highlighted while it runs
        self.assertTrue(any("c:/ROOT/SCAN" in ids for ids in seen), seen)

    def test_2_userdata_panel(self):
        text = self.poll(lambda: (lambda t: t if '"counter"' in t else None)(
            self.browser.eval("document.getElementById('userdata').textContent")))
        self.assertIsNotNone(text)
        data = json.loads(text)
        self.assertIn("doing", data)
        self.assertIsInstance(data["counter"], int)

    def test_3_set_initial_state_from_page(self):
        clicked = self.browser.eval(
            "(() => { const n = document.getElementById('s:/ROOT/REPORT'); if (!n) return false;"
            " n.dispatchEvent(new MouseEvent('click', {bubbles: true}));"
            " const b = document.getElementById('set-initial'); if (b.disabled) return false; b.click(); return true; })()")
        self.assertTrue(clicked)
        ok = self.poll(lambda: any(i == ["REPORT"] for i in list(self.initials)), timeout=10)
        self.assertTrue(ok, "the machine's initial state did not change")
        msg = self.poll(lambda: self.browser.eval("document.getElementById('init-result').textContent"), timeout=5)
        self.assertIn("REPORT", msg)

    def test_4_no_external_downloads(self):
        urls = self.browser.requested_urls()
        self.assertTrue(urls)
        for url in urls:
            self.assertTrue(url.startswith(self.base) or url.startswith("about:") or url.startswith("data:"), url)


if __name__ == "__main__":
    rospy.init_node("test_web_viewer")
    rostest.rosrun("smach_viewer", "web_viewer", TestWebViewer)
