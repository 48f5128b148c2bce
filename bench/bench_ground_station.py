#!/usr/bin/env python3
"""Benchmark of the web ground station during simulated trials (tools/run_mission.sh, short trials).

Figures (all measured in this run, side by side):
* the mission's real-time factor with the ground station off (GCS=0), on with no page open, and on with one
  page open in headless Chromium; rounds alternate the three, so machine load hits them alike. A Chromium
  on about:blank runs in every variant (started before the trial), so the "one_page" difference is the
  page's own cost. The drop with one page open is the target (<= 5 %). CPU seconds of the ground station
  node and of Chromium too.
* 20 pages at once: 20 event-stream clients (what a page's EventSource does) plus one Chromium page on a
  running trial: each frame's lag (receive time - the time the node built it), the frame rate every client
  got, and the node's memory (RSS) at the start and the end.
Writes bench/results/ground_station.json.

    python bench/bench_ground_station.py [--rounds 2] [--duration 150] [--rtf 4] [--pages 20] [--watch 60]

Short trials (150 sim s, not 1200): on this 2-core machine other work runs beside the benchmark.
"""
import argparse
import http.client
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time

from _common import ROOT, SRC, load_averages, write_result
from _node_cpu import NodeCpuSampler

sys.path.insert(0, os.path.join(SRC, "smach_viewer", "test"))
from cdp import HeadlessChromium  # noqa: E402  (the SMACH viewer tests' DevTools client)

ADDRESS = re.compile(r"ground station on http://127\.0\.0\.1:(\d+)/")
WALL = re.compile(rb'"wall":([0-9.]+)')
WARM_UP_S = 3.0   # lags of the first seconds (20 pages connecting at once) are reported apart
VARIANTS = ("off", "no_page", "one_page")


class Sampler(NodeCpuSampler):
    """NodeCpuSampler that also remembers which pids are the ground station node."""

    def __init__(self, root_pid):
        super().__init__(root_pid)
        self.station = set()

    def sample(self):
        super().sample()
        for pid in self.cpu:
            if pid not in self.station:
                try:
                    with open(f"/proc/{pid}/cmdline", "rb") as f:
                        if b"mbzirc_ground_station" in f.read() and pid not in self.station:
                            self.station.add(pid)
                except OSError:
                    pass

    def station_cpu(self):
        return round(sum(self.cpu[p] for p in self.station), 2)


class Mission:
    """One run of tools/run_mission.sh; `port` is the ground station's once it printed it."""

    def __init__(self, args, gcs, out):
        cmd = ["bash", os.path.join(ROOT, "tools", "run_mission.sh"), "SEED=%d" % args.seed, "UAVS=3",
               "RTF=%s" % args.rtf, "DURATION=%d" % args.duration, "OUT=%s" % out, "GCS=%d" % int(gcs),
               "GCS_PORT=0"]
        self.out = out
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.port = None
        self.got_port = threading.Event()
        self.sampler = Sampler(self.proc.pid).start()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.proc.stdout:
            m = ADDRESS.search(line)
            if m:
                self.port = int(m.group(1))
                self.got_port.set()

    def wait(self):
        self.proc.wait()
        self.sampler.stop()
        with open(os.path.join(self.out, "summary.json")) as f:
            return json.load(f)


def start_browser(attempts=3):
    """Headless Chromium on about:blank, and a sampler of its CPU (a fresh browser per attempt: under load a
    starting Chromium sometimes misses its first DevTools call)."""
    for attempt in range(attempts):
        browser = HeadlessChromium()
        try:
            browser.open("about:blank")
            return browser, NodeCpuSampler(browser.proc.pid).start()
        except Exception:  # noqa: BLE001
            close_browser(browser)
            if attempt == attempts - 1:
                raise


def close_browser(browser):
    """Close Chromium and wait for its DevTools reader thread to end: a reader still blocked on the closed
    pipe's descriptor number would read the next browser's answers once the number is reused."""
    browser.close()
    browser._reader.join(10)


def show_station(browser, port):
    browser.send("Page.navigate", {"url": "http://127.0.0.1:%d/" % port}, session=browser.session)


def run_variant(variant, args, tmp, i, attempts=2):
    """One trial of a variant; a trial that wrote no summary (e.g. its master did not start in time under
    load) is run again once, and said so."""
    for attempt in range(attempts):
        try:
            return run_variant_once(variant, args, os.path.join(tmp, "%s_%d_%d" % (variant, i, attempt)))
        except (OSError, RuntimeError) as ex:
            print("  %-9s failed (%s)%s" % (variant, ex, ", again" if attempt < attempts - 1 else ""), flush=True)
            if attempt == attempts - 1:
                raise


def run_variant_once(variant, args, out):
    """Every variant has a Chromium running (started before the trial, on about:blank): only in "one_page"
    does it show the station, so the difference is the page's own cost, not a browser's start-up."""
    browser, sampler = start_browser()
    mission = None
    try:
        mission = Mission(args, variant != "off", out)
        if variant == "one_page":
            if not mission.got_port.wait(120):
                raise RuntimeError("the ground station never printed its address")
            show_station(browser, mission.port)
        summary = mission.wait()
    except BaseException:
        sampler.stop()
        close_browser(browser)
        raise
    finally:
        if mission is not None and mission.proc.poll() is None:
            mission.proc.terminate()
            mission.proc.wait()
    row = {"variant": variant, "rtf": summary["real_time_factor"], "sim_s": summary["sim_time_s"],
           "wall_s": summary["wall_time_s"], "station_cpu_s": mission.sampler.station_cpu()}
    row["page_frames"] = browser.eval("window.gcs ? window.gcs.frames : 0")
    sampler.stop()
    row["chromium_cpu_s"] = sampler.cpu_by_kind()["total"]
    close_browser(browser)
    print("  %-9s rtf %.3f  (sim %.0f s in %.0f s wall)  station %.1f CPU-s  chromium %.1f CPU-s, %d frames" % (
        variant, row["rtf"], row["sim_s"], row["wall_s"], row["station_cpu_s"], row["chromium_cpu_s"],
        row["page_frames"]), flush=True)
    return row


class EventClient(threading.Thread):
    """Reads the event stream like a page does; records each frame's lag and its arrival time."""

    def __init__(self, port, stop):
        super().__init__(daemon=True)
        self.port, self.stop = port, stop
        self.lags, self.arrivals = [], []

    def run(self):
        c = http.client.HTTPConnection("127.0.0.1", self.port, timeout=10)
        c.request("GET", "/api/events", headers={"Host": "127.0.0.1:%d" % self.port})
        r = c.getresponse()
        event = None
        while not self.stop.is_set():
            line = r.fp.readline()
            if not line:
                break
            if line.startswith(b"event: "):
                event = line[7:].strip()
            elif line.startswith(b"data: ") and event == b"frame":
                now = time.time()
                wall = WALL.search(line, max(0, len(line) - 80))   # the frame ends with ...,"wall":<s>}
                self.lags.append(now - float(wall.group(1)))
                self.arrivals.append(now)
        c.close()


def rss_kb(pids):
    total = 0
    for pid in pids:
        try:
            with open(f"/proc/{pid}/status") as f:
                total += next(int(x.split()[1]) for x in f if x.startswith("VmRSS:"))
        except (OSError, StopIteration):
            pass
    return total


def many_pages(args, tmp):
    """args.pages event-stream clients + one Chromium page on one running trial, for args.watch seconds."""
    # the trial outlasts the 20 s start-up wait, the watch and Chromium's start (a run at 30 s of margin ended
    # before the last memory sample)
    long_enough = argparse.Namespace(**dict(vars(args), duration=int(max(args.duration, (args.watch + 60) * args.rtf))))
    mission = Mission(long_enough, True, os.path.join(tmp, "pages"))
    if not mission.got_port.wait(120):
        raise RuntimeError("the ground station never printed its address")
    time.sleep(20)  # the start-up of a dozen nodes starves a starting Chromium on 2 cores
    rss_start = rss_kb(mission.sampler.station)
    browser, _ = start_browser()
    show_station(browser, mission.port)
    stop = threading.Event()
    clients = [EventClient(mission.port, stop) for _ in range(args.pages)]
    for c in clients:
        c.start()
    page_lags = []
    rss = []
    end = time.monotonic() + args.watch
    while time.monotonic() < end and mission.proc.poll() is None:
        time.sleep(1.0)
        try:
            lag = browser.eval("window.gcs.lag")
        except Exception as ex:  # noqa: BLE001 - a DevTools call that timed out under load: say so
            print("  chromium did not answer: %s" % ex, flush=True)
            lag = None
        if lag is not None:
            page_lags.append(lag)
        if mission.proc.poll() is None:      # once the trial has ended the node is gone (0 kB): not a sample
            rss.append(rss_kb(mission.sampler.station))
    stop.set()
    close_browser(browser)
    mission.proc.terminate()
    mission.proc.wait()
    mission.sampler.stop()
    t_open = min(c.arrivals[0] for c in clients if c.arrivals)
    lags = [x for c in clients for x, t in zip(c.lags, c.arrivals) if t - t_open > WARM_UP_S]
    connect_lags = [x for c in clients for x, t in zip(c.lags, c.arrivals) if t - t_open <= WARM_UP_S]
    rates = [(len(c.arrivals) - 1) / (c.arrivals[-1] - c.arrivals[0]) for c in clients if len(c.arrivals) > 2]
    return {
        "clients": args.pages, "chromium_pages": 1, "watched_s": args.watch,
        "frames_received": len(lags),
        "lag_s": {"median": round(statistics.median(lags), 3), "p99": round(sorted(lags)[int(0.99 * len(lags))], 3),
                  "max": round(max(lags), 3)},
        "lag_s_while_connecting_max": round(max(connect_lags), 3), "warm_up_s": WARM_UP_S,
        "chromium_page_lag_s_max": round(max(page_lags), 3) if page_lags else None,
        "frames_per_s_per_client": {"min": round(min(rates), 1), "mean": round(statistics.mean(rates), 1)},
        "station_rss_mb": {"start": round(rss_start / 1024, 1), "end": round(rss[-1] / 1024, 1),
                           "max": round(max(rss) / 1024, 1)},
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--duration", type=int, default=150)
    ap.add_argument("--rtf", type=float, default=4.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--pages", type=int, default=20)
    ap.add_argument("--watch", type=float, default=60.0)
    args = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="bench_gcs_")
    load_before = load_averages()
    rows = []
    for i in range(args.rounds):
        print("round %d/%d" % (i + 1, args.rounds), flush=True)
        for variant in VARIANTS:
            rows.append(run_variant(variant, args, tmp, i))
    rtf = drop = None
    if rows:   # --rounds 0: the pages part only
        rtf = {v: round(statistics.mean(r["rtf"] for r in rows if r["variant"] == v), 3) for v in VARIANTS}
        drop = {v: round(100.0 * (1.0 - rtf[v] / rtf["off"]), 1) for v in VARIANTS[1:]}
        print("mean rtf: %s; drop vs off: %s %%" % (rtf, drop), flush=True)
    print("%d pages at once..." % args.pages, flush=True)
    pages = many_pages(args, tmp)
    print(json.dumps(pages, indent=1), flush=True)
    result = {
        "trial": {"seed": args.seed, "uavs": 3, "ugv": True, "rtf_requested": args.rtf, "duration_s": args.duration},
        "runs": rows, "mean_rtf": rtf, "rtf_drop_percent": drop,
        "one_page_target_met": drop["one_page"] <= 5.0 if drop else None,
        "pages": pages,
        "pages_target_met": pages["lag_s"]["max"] <= 1.0,
        "load_average_before": load_before, "load_average_after": load_averages(),
    }
    write_result("ground_station", result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
