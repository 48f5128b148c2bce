#!/usr/bin/env python3
"""rostest: the web viewer page in headless Chromium follows a running machine (smach_demo), and debugs it.

Checks that the highlighted state in the browser changes as the machine runs, and only to states the
machine really entered (cross-checked with the status topic), that nested containers highlight, that the
userdata panel shows the machine's userdata, that "Set as initial state" reaches the machine, and that the
page loads nothing from outside the viewer. The debugger, from the page: a breakpoint set by clicking
stops the machine there (the status topic stays on that state), a forced outcome moves it on without
running the state (its counter does not move); both children of a Concurrence pause and show at once;
the search box and a collapsed container; a server that does not allow debugging is shown as such.
SMACH_VIEWER_SCREENSHOT=<png> saves a picture of the debugger with the machine paused.
"""
import json
import os
import sys
import threading
import time
import unittest
import urllib.error
import urllib.request

import rospy
import rostest
from smach_msgs.msg import SmachContainerStatus

from cdp import HeadlessChromium

SERVER = "/smach_demo/demo"
LOCKED = "/smach_demo_locked/demo"
PAUSED_JS = "JSON.stringify(Array.from(document.querySelectorAll('#graph g.paused')).map(e => e.id))"
ACTIVE_JS = "JSON.stringify(Array.from(document.querySelectorAll('#graph g.active')).map(e => e.id))"


class TestWebViewer(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.truth = set()       # ids of states the machine really had active
        cls.initials = []
        cls.root_statuses = []  # (monotonic time, active states, local_data) of /ROOT
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
            if msg.path == "/ROOT":
                cls.root_statuses.append((time.monotonic(), list(msg.active_states), msg.local_data))
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

    # ---- debugger -------------------------------------------------------------------------------
    def click_state(self, state_id):
        return self.browser.eval(
            "(() => { const n = document.getElementById(%s); if (!n) return false;"
            " n.dispatchEvent(new MouseEvent('click', {bubbles: true})); return true; })()" % json.dumps(state_id))

    def page_debug(self):
        return json.loads(self.browser.eval("JSON.stringify(snap.servers[%s].debug)" % json.dumps(SERVER)) or "null")

    def toggle_breakpoint(self, path, on):
        self.assertTrue(self.poll(lambda: self.click_state("s:" + path)), "no node for %s" % path)
        self.assertTrue(self.poll(lambda: self.browser.eval(
            "(() => { const b = document.getElementById('bp-toggle'); if (b.disabled) return false; b.click(); return true; })()"),
            timeout=5))
        ok = self.poll(lambda: (path in (self.page_debug() or {}).get("breakpoints", [])) == on, timeout=10)
        self.assertTrue(ok, "breakpoint on %s not %s; server's last answer %s; page: %s" % (
            path, on, (self.page_debug() or {}).get("last"), self.browser.eval("document.getElementById('dbg-result').textContent")))

    def counter_of(self, local_data):
        from smach_ros.userdata_codec import decode_local_data
        return decode_local_data(local_data)["counter"]

    def test_5_breakpoint_stop_force_outcome_go_on(self):
        self.assertIn("Debugger on", self.browser.eval("document.getElementById('dbg-state').textContent"))
        self.toggle_breakpoint("/ROOT/REPORT", True)
        paused = self.poll(lambda: "s:/ROOT/REPORT" in json.loads(self.browser.eval(PAUSED_JS) or "[]"), timeout=20)
        self.assertTrue(paused, "the page never showed REPORT paused")
        # the machine really stopped there: REPORT stays active on the status topic (it runs 0.3 s otherwise)
        time.sleep(1.5)
        with self.lock:
            statuses = list(self.root_statuses)
        last_t, last_active, last_data = statuses[-1]
        self.assertEqual(last_active, ["REPORT"])
        first = len(statuses) - 1  # the first status of the current stay in REPORT
        while first > 0 and statuses[first - 1][1] == ["REPORT"]:
            first -= 1
        self.assertLess(statuses[first][0], time.monotonic() - 1.4, "REPORT was left: the machine did not stop")
        counter = self.counter_of(last_data)
        inspector = self.browser.eval("document.getElementById('dbg-userdata').textContent")
        self.assertIn("counter: %d" % counter, inspector.splitlines())
        if os.environ.get("SMACH_VIEWER_SCREENSHOT"):
            self.browser.screenshot(os.environ["SMACH_VIEWER_SCREENSHOT"])
        # clearing the breakpoint does not release the paused state; then force 'again' from the page:
        # REPORT does not run (counter unchanged) and the machine goes on to PATROL
        self.toggle_breakpoint("/ROOT/REPORT", False)
        self.assertEqual([p["path"] for p in self.page_debug()["paused"]], ["/ROOT/REPORT"])
        mark = time.monotonic()
        self.assertTrue(self.browser.eval(
            "(() => { const b = document.querySelector('.paused-item[data-path=\"/ROOT/REPORT\"] button.force[data-outcome=\"again\"]');"
            " if (!b) return false; b.click(); return true; })()"))

        def moved_on():
            with self.lock:
                return [(a, d) for t, a, d in self.root_statuses if t > mark and a == ["PATROL"]]
        after = self.poll(moved_on, timeout=20)
        self.assertTrue(after, "the machine did not go on to PATROL after the forced outcome")
        self.assertEqual(self.counter_of(after[0][1]), counter, "REPORT ran although its outcome was forced")
        # without the breakpoint it goes round again and REPORT really runs
        self.assertTrue(self.poll(lambda: any(
            a == ["PATROL"] and self.counter_of(d) == counter + 1 for t, a, d in list(self.root_statuses) if t > mark),
            timeout=20))

    def test_6_concurrence_children_pause_together(self):
        for child in ("CAMERA", "THERMAL"):
            self.toggle_breakpoint("/ROOT/WATCH/" + child, True)
        both = {"s:/ROOT/WATCH/CAMERA", "s:/ROOT/WATCH/THERMAL"}
        self.assertTrue(self.poll(lambda: both <= set(json.loads(self.browser.eval(PAUSED_JS) or "[]")), timeout=20),
                        "both concurrent children did not show paused at once")
        self.assertTrue(both <= set(json.loads(self.browser.eval(ACTIVE_JS) or "[]")))
        items = json.loads(self.browser.eval(
            "JSON.stringify(Array.from(document.querySelectorAll('.paused-item')).map(e => e.dataset.path))"))
        self.assertEqual(sorted(items), ["/ROOT/WATCH/CAMERA", "/ROOT/WATCH/THERMAL"])
        for child in ("CAMERA", "THERMAL"):
            self.toggle_breakpoint("/ROOT/WATCH/" + child, False)
        self.browser.eval("document.getElementById('dbg-continue').click()")
        self.assertTrue(self.poll(lambda: not (self.page_debug() or {}).get("paused"), timeout=10))

    def test_7_search_and_collapse(self):
        self.browser.eval("(() => { const s = document.getElementById('search'); s.value = 'look';"
                          " s.dispatchEvent(new Event('input')); })()")
        matches = json.loads(self.browser.eval(
            "JSON.stringify(Array.from(document.querySelectorAll('#graph g.match')).map(e => e.id).sort())"))
        self.assertEqual(matches, ["s:/ROOT/SCAN/LOOK_LEFT", "s:/ROOT/SCAN/LOOK_RIGHT"])
        self.browser.eval("(() => { const s = document.getElementById('search'); s.value = '';"
                          " s.dispatchEvent(new Event('input')); })()")
        self.browser.eval("document.getElementById('c:/ROOT/SCAN').dispatchEvent(new MouseEvent('dblclick', {bubbles: true}))")
        folded = self.poll(lambda: self.browser.eval(
            "!!document.getElementById('s:/ROOT/SCAN') && !document.getElementById('s:/ROOT/SCAN/LOOK_LEFT')"), timeout=10)
        self.assertTrue(folded, "SCAN did not collapse into one node")
        # the collapsed node lights up while the machine is inside it
        self.assertTrue(self.poll(lambda: "s:/ROOT/SCAN" in json.loads(self.browser.eval(ACTIVE_JS) or "[]"),
                                  timeout=20))
        self.browser.eval("document.getElementById('s:/ROOT/SCAN').dispatchEvent(new MouseEvent('dblclick', {bubbles: true}))")
        self.assertTrue(self.poll(lambda: self.browser.eval("!!document.getElementById('s:/ROOT/SCAN/LOOK_LEFT')"),
                                  timeout=10))

    def test_8_locked_server_says_debugging_is_off(self):
        self.browser.eval("(() => { const s = document.getElementById('server'); s.value = %s;"
                          " s.dispatchEvent(new Event('change')); })()" % json.dumps(LOCKED))
        text = self.poll(lambda: (lambda t: t if "off" in t else None)(
            self.browser.eval("document.getElementById('dbg-state').textContent")), timeout=10)
        self.assertIn("Debugging is off on this server", text or "")
        self.assertTrue(self.browser.eval("document.getElementById('dbg-controls').hidden"))
        req = urllib.request.Request(self.base + "/api/debug", method="POST", headers={"Content-Type": "application/json"},
                                     data=json.dumps({"server": LOCKED, "cmd": "pause"}).encode())
        with self.assertRaises(urllib.error.HTTPError) as ex:
            urllib.request.urlopen(req, timeout=5)
        self.assertEqual(ex.exception.code, 400)
        self.assertIn("not allowed", json.loads(ex.exception.read())["error"])
        # nor does it accept container_init: "Set as initial state" says so instead of sending into the void
        req = urllib.request.Request(self.base + "/api/set_initial_state", method="POST",
                                     headers={"Content-Type": "application/json"},
                                     data=json.dumps({"server": LOCKED, "path": "/ROOT", "state": "REPORT"}).encode())
        with self.assertRaises(urllib.error.HTTPError) as ex:
            urllib.request.urlopen(req, timeout=5)
        self.assertIn("does not accept container_init", json.loads(ex.exception.read())["error"])


if __name__ == "__main__":
    rospy.init_node("test_web_viewer")
    rostest.rosrun("smach_viewer", "web_viewer", TestWebViewer)
