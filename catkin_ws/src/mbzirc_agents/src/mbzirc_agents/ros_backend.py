"""The ROS side of the framework: rospy and actionlib behind the small backend interface.

Why a backend: the framework's logic (dispatch, busy rejection, preemption, results) is tested with a
fake backend and no ROS master; this class is the only place that makes real ROS objects for it.
"""
from __future__ import annotations

import time
from typing import Any, Callable

import actionlib
import rospy

from .bounded_call import BoundedCall

SERVICE_TIMEOUT = 5.0    # s (wall) before a service call of an agent gives up


class RosBackend:
    """rospy implementation of the backend used by AgentInterface and Agent."""

    def subscriber(self, topic: str, msg_type: Any, callback: Callable[[Any], None]) -> Any:
        """A rospy.Subscriber with a small queue (we only want fresh data)."""
        return rospy.Subscriber(topic, msg_type, callback, queue_size=10)

    def publisher(self, topic: str, msg_type: Any, latch: bool = False) -> Any:
        """A rospy.Publisher."""
        return rospy.Publisher(topic, msg_type, queue_size=10, latch=latch)

    def service(self, name: str, srv_type: Any, handler: Callable[[Any], Any]) -> Any:
        """A rospy.Service."""
        return rospy.Service(name, srv_type, handler)

    def service_proxy(self, name: str, srv_type: Any) -> Any:
        """A rospy.ServiceProxy (not persistent: the server may restart), bounded in wall time
        (`~service_timeout`, 5 s; see bounded_call)."""
        timeout = float(rospy.get_param('~service_timeout', SERVICE_TIMEOUT))
        return BoundedCall(name, rospy.ServiceProxy(name, srv_type), timeout)

    def action_server(self, name: str, action: Any, execute_cb: Callable[[Any], None]) -> Any:
        """A started actionlib SimpleActionServer."""
        server = actionlib.SimpleActionServer(name, action, execute_cb=execute_cb, auto_start=False)
        server.start()
        return server

    def timer(self, period: float, callback: Callable[[Any], None]) -> Any:
        """A rospy.Timer (sim time aware)."""
        return rospy.Timer(rospy.Duration(period), callback)

    def now(self) -> float:
        """Current ROS time in seconds (sim time when /use_sim_time)."""
        return rospy.get_time()

    def sleep(self, seconds: float) -> None:
        """Sleep `seconds` of ROS time; returns quietly on shutdown or when sim time jumps back, and after
        at most 2 x `seconds` + 1 s of wall time (never sooner than ROS time at a real-time factor >= 0.5).
        Why the wall bound: in simulation /clock comes from the ground station and stops when the robot's
        link is cut; a task asleep on it would never see the preempt of the heartbeat watchdog's safe stop
        (mbzirc_robustness fault suite, permanently cut UAV)."""
        start = rospy.get_time()
        end_wall = time.monotonic() + 2.0 * max(float(seconds), 0.0) + 1.0
        while not rospy.is_shutdown():
            now = rospy.get_time()
            if now - start >= seconds or now < start or time.monotonic() >= end_wall:
                return
            time.sleep(min(0.01, max(seconds - (now - start), 0.001)))

    def wall_time(self) -> float:
        """Monotonic wall-clock seconds (the heartbeat watchdog's clock: it must run when /clock stops)."""
        return time.monotonic()

    def wait_event(self, event: Any, timeout: float) -> bool:
        """threading.Event.wait in wall time (the unit tests' fake backend waits on its simulated clock)."""
        return event.wait(timeout)

    def is_shutdown(self) -> bool:
        """rospy.is_shutdown."""
        return rospy.is_shutdown()

    def loginfo(self, msg: str) -> None:
        rospy.loginfo(msg)

    def loginfo_throttle(self, period: float, msg: str) -> None:
        rospy.loginfo_throttle(period, msg)

    def logerr_throttle(self, period: float, msg: str) -> None:
        rospy.logerr_throttle(period, msg)

    def logerr(self, msg: str) -> None:
        rospy.logerr(msg)

    def logwarn(self, msg: str) -> None:
        rospy.logwarn(msg)
