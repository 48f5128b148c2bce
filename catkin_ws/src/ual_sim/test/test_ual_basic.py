#!/usr/bin/env python3
"""rostest: every UAV takes off, goes to a waypoint and lands within tolerance, reporting the UAL states in
order; the UGV drives to a waypoint; bad requests (take-off while flying, waypoint outside the arena, NaN)
are refused without killing the simulator."""
import math
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from rosgraph_msgs.msg import Clock
from uav_abstraction_layer.msg import State
from uav_abstraction_layer.srv import GoToWaypoint, Land, TakeOff

TOL = 0.2


class StateLog:
    """Records the sequence of distinct UAL states and the last pose of one robot."""

    def __init__(self, ns: str):
        self.states, self.pose, self.lock = [], None, threading.Lock()
        rospy.Subscriber(f"/{ns}/ual/state", State, self.on_state, queue_size=50)
        rospy.Subscriber(f"/{ns}/ual/pose", PoseStamped, self.on_pose, queue_size=1)

    def on_state(self, m: State) -> None:
        with self.lock:
            if not self.states or self.states[-1] != m.state:
                self.states.append(m.state)

    def on_pose(self, m: PoseStamped) -> None:
        self.pose = m


def wait(cond, timeout=30.0):
    """Poll cond in wall time (the sim may run faster than real time)."""
    end = time.time() + timeout
    while time.time() < end and not rospy.is_shutdown():
        if cond():
            return True
        time.sleep(0.02)
    return False


def waypoint(x, y, z, yaw=0.0, frame="arena"):
    p = PoseStamped()
    p.header.frame_id = frame
    p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, z
    p.pose.orientation.z, p.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return p


class TestUalBasic(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_ual_basic")
        rospy.wait_for_message("/clock", Clock, timeout=30)

    def fly(self, rid: int, goal):
        ns = f"mbzirc2020_{rid}"
        log = StateLog(ns)
        for s in ("take_off", "go_to_waypoint", "land"):
            rospy.wait_for_service(f"/{ns}/ual/{s}", timeout=30)
        self.assertTrue(wait(lambda: log.pose is not None and log.states), f"{ns}: no pose/state")
        start = log.pose.pose.position
        self.assertEqual(log.states[-1], State.LANDED_DISARMED)
        rospy.ServiceProxy(f"/{ns}/ual/take_off", TakeOff)(3.0, True)
        self.assertTrue(wait(lambda: log.states[-1] == State.FLYING_AUTO, 10))
        self.assertAlmostEqual(log.pose.pose.position.z, start.z + 3.0, delta=TOL)
        # take-off while flying: refused, nothing changes, node alive
        rospy.ServiceProxy(f"/{ns}/ual/take_off", TakeOff)(3.0, True)
        # outside the arena and NaN: refused
        go = rospy.ServiceProxy(f"/{ns}/ual/go_to_waypoint", GoToWaypoint)
        go(waypoint(500.0, 0.0, 3.0), True)
        go(waypoint(float("nan"), 0.0, 3.0), True)
        self.assertLess(abs(log.pose.pose.position.x - start.x), TOL)
        go(waypoint(*goal, yaw=0.5), True)
        wait(lambda: math.dist((log.pose.pose.position.x, log.pose.pose.position.y, log.pose.pose.position.z),
                               goal) < TOL, 5)
        p = log.pose.pose.position
        self.assertLess(math.dist((p.x, p.y, p.z), goal), TOL, f"{ns} at {p} not at {goal}")
        q = log.pose.pose.orientation
        self.assertAlmostEqual(2 * math.atan2(q.z, q.w), 0.5, delta=0.1)
        rospy.ServiceProxy(f"/{ns}/ual/land", Land)(True)
        self.assertTrue(wait(lambda: log.states[-1] == State.LANDED_DISARMED, 10))
        self.assertLess(log.pose.pose.position.z, 0.05)
        # states in the UAL order (duplicates removed)
        self.assertEqual(log.states, [State.LANDED_DISARMED, State.TAKING_OFF, State.FLYING_AUTO,
                                      State.LANDING, State.LANDED_DISARMED], f"{ns}: {log.states}")

    def test_1_uav1(self):
        self.fly(1, (-4.0, 3.0, 4.0))

    def test_2_uav2(self):
        self.fly(2, (2.0, -3.0, 5.0))

    def test_3_uav3(self):
        self.fly(3, (3.0, 6.0, 3.5))

    def test_4_ugv(self):
        log = StateLog("mbzirc2020_0")
        rospy.wait_for_service("/mbzirc2020_0/ual/go_to_waypoint", timeout=30)
        self.assertTrue(wait(lambda: log.pose is not None))
        rospy.ServiceProxy("/mbzirc2020_0/ual/go_to_waypoint", GoToWaypoint)(waypoint(8.0, -4.0, 0.0), True)
        wait(lambda: abs(log.pose.pose.position.x - 8.0) < TOL, 5)
        self.assertLess(math.hypot(log.pose.pose.position.x - 8.0, log.pose.pose.position.y + 4.0), TOL)
        self.assertIn(State.FLYING_AUTO, log.states)
        self.assertEqual(log.states[-1], State.LANDED_ARMED)


if __name__ == "__main__":
    rostest.rosrun("ual_sim", "ual_basic", TestUalBasic)
