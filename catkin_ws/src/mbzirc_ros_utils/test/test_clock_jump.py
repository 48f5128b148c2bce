#!/usr/bin/env python3
"""rostest helper: drives /clock itself (sim time from 1000 s at real time), sends one /clock message
10 s in the past (and later one 300 s ahead) once `~topic` is flowing, and checks that `~topic` is still
published after each jump.

Reusable by any package: `<test pkg="mbzirc_ros_utils" type="test_clock_jump.py">` with `~topic` (the
periodic output to watch, any type), `~min_after` (messages required in `~watch_s` wall seconds after each
jump, default 3 in 4 s), `~expect_dead` (false; true for a negative control: the output must stop), `~start` (1000 s: sim
time of the first /clock; give a later test in the same launch a larger one)."""
import threading
import time
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Clock
from rospy.msg import AnyMsg


class ClockDriver:
    """Publishes /clock at 50 Hz wall; `jump(dt)` moves sim time by dt at once."""

    def __init__(self, start: float) -> None:
        self.pub = rospy.Publisher('/clock', Clock, queue_size=10)
        self.sim = start
        self.lock = threading.Lock()
        threading.Thread(target=self._run, daemon=True).start()

    def _run(self) -> None:
        last = time.monotonic()
        while not rospy.core.is_shutdown():
            time.sleep(0.02)
            now = time.monotonic()
            with self.lock:
                self.sim += now - last
                t = self.sim
            last = now
            self.pub.publish(Clock(clock=rospy.Time.from_sec(t)))

    def jump(self, dt: float) -> None:
        with self.lock:
            self.sim += dt


class TestClockJump(unittest.TestCase):
    def test_output_survives_clock_jumps(self):
        rospy.init_node('test_clock_jump')
        topic = rospy.get_param('~topic')
        min_after = int(rospy.get_param('~min_after', 3))
        watch_s = float(rospy.get_param('~watch_s', 4.0))
        expect_dead = bool(rospy.get_param('~expect_dead', False))
        clock = ClockDriver(float(rospy.get_param('~start', 1000.0)))
        stamps = []
        rospy.Subscriber(topic, AnyMsg, lambda _m: stamps.append(time.monotonic()))
        deadline = time.monotonic() + 60.0
        while len(stamps) < 3 and time.monotonic() < deadline:
            time.sleep(0.1)
        self.assertGreaterEqual(len(stamps), 3, f'{topic} never flowed before the jumps')
        for dt in (-10.0, 300.0):
            time.sleep(0.5)
            jumped = time.monotonic()
            clock.jump(dt)
            time.sleep(watch_s)
            after = sum(1 for s in stamps if s > jumped + 0.5)
            if expect_dead:
                self.assertEqual(after, 0, f'{topic} kept flowing after a {dt:+.0f} s jump (control)')
                return
            self.assertGreaterEqual(after, min_after, f'{topic}: {after} messages in {watch_s} s after a '
                                                      f'{dt:+.0f} s /clock jump (need {min_after})')


if __name__ == '__main__':
    rostest.rosrun('mbzirc_ros_utils', 'test_clock_jump', TestClockJump)
