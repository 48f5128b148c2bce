"""Helpers of the Chromium rostests: open the ground station page and read what it shows."""
import json
import os
import sys
import time

import rospkg

# the tiny DevTools client of the SMACH viewer's tests (no websocket library needed)
sys.path.insert(0, os.path.join(rospkg.RosPack().get_path("smach_viewer"), "test"))
from cdp import HeadlessChromium  # noqa: E402

# What the page shows: frame time, every robot marker converted back from canvas pixels to metres, the fire
# list as displayed (id -> status text), the replay timeline.
SHOWN_JS = """JSON.stringify({
  frames: window.gcs.frames, t: window.gcs.frame ? window.gcs.frame.t : null,
  replay: window.gcs.frame ? window.gcs.frame.replay || null : null,
  robots: Object.fromEntries(Object.entries(window.gcs.drawn.robots).map(
    ([k, v]) => [k, window.gcs.toWorld(v.px, v.py).concat([v.stale, v.stamp])])),
  fires: Object.fromEntries(Array.from(document.querySelectorAll('#fires .fire')).map(
    (e) => [e.dataset.fire, e.querySelector('.fstatus').textContent])),
  conn: document.getElementById('conn').textContent})"""


class StationPage:
    """Headless Chromium showing the ground station at base_url."""

    def __init__(self, base_url, width=1400, height=850, attempts=3):
        for attempt in range(attempts):   # a Chromium starting on a busy machine may miss its first calls
            self.browser = HeadlessChromium()
            try:
                self.browser.open(base_url + "/")
                break
            except Exception:  # noqa: BLE001
                self.browser.close()
                if attempt == attempts - 1:
                    raise
        self.browser.send("Emulation.setDeviceMetricsOverride", {"width": width, "height": height,
                                                                  "deviceScaleFactor": 1, "mobile": False},
                          session=self.browser.session)

    def shown(self):
        return json.loads(self.browser.eval(SHOWN_JS))

    def wait_for(self, predicate, timeout, what):
        deadline = time.monotonic() + timeout
        last = None
        while time.monotonic() < deadline:
            try:
                last = self.shown()
                if predicate(last):
                    return last
            except Exception as ex:  # noqa: BLE001 - page still loading
                last = ex
            time.sleep(0.1)
        raise AssertionError("page never showed %s; last: %s" % (what, last))

    def eval(self, js):
        return self.browser.eval(js)

    def screenshot(self, path):
        import base64
        data = self.browser.send("Page.captureScreenshot", {"format": "png"}, session=self.browser.session)["data"]
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))

    def close(self):
        self.browser.close()
