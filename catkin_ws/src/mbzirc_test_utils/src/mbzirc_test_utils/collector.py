"""Collecting what a node under test publishes, and the robot id its namespace stands for."""
from __future__ import annotations

import threading
import time
from typing import Optional

import rospy


class Collector:
    """Subscribes to a topic and keeps every message (or only its arrival time) for the test to check.

    The callback runs in rospy's thread while the test thread reads: the lock keeps the two apart.
    `keep=False` stores arrival times only (for image streams, whose messages the test never reads).
    """

    def __init__(self, topic: str, cls, keep: bool = True, queue_size: int = 50):
        self.msgs: list = []
        self.times: list = []
        self.keep = keep
        self.lock = threading.Lock()
        self.sub = rospy.Subscriber(topic, cls, self.cb, queue_size=queue_size)

    def cb(self, msg) -> None:
        with self.lock:
            self.times.append(time.time())
            if self.keep:
                self.msgs.append(msg)

    def count(self) -> int:
        with self.lock:
            return len(self.times)

    def last_time(self) -> Optional[float]:
        """Wall time of the latest message, None before the first one."""
        with self.lock:
            return self.times[-1] if self.times else None

    def wait(self, n: int, timeout: float) -> bool:
        """Waits until n messages arrived (or timeout / shutdown); True when they did."""
        end = time.time() + timeout
        while time.time() < end and self.count() < n and not rospy.is_shutdown():
            time.sleep(0.05)
        return self.count() >= n


def agent_id(namespace: str) -> str:
    """The agent id of a robot namespace ("/mbzirc2020_2/" -> "2"), as the detectors put in agent_id."""
    return namespace.strip("/").rsplit("_", 1)[-1]
