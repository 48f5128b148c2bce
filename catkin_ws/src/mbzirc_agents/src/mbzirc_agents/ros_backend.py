"""The ROS side of the framework: rospy and actionlib behind the small backend interface.

Why a backend: the framework's logic (dispatch, busy rejection, preemption, results) is tested with a
fake backend and no ROS master; this class is the only place that makes real ROS objects for it.
"""
from __future__ import annotations

import sys
import threading
import time
from typing import Any, Callable

import actionlib
import rospy

from .bounded_call import BoundedCall
from .ros_time_scheduler import RosTimeScheduler

SERVICE_TIMEOUT = 5.0    # s (wall) before a service call of an agent gives up
#: s of ROS time between two status messages of an idle action server (actionlib's default: 0.2). A goal's
#: transitions are published at once anyway; the periodic message only tells a client the server exists,
#: and the central unit received 5 a second from each of ~40 servers.
ACTION_STATUS_PERIOD = 1.0


def _publish_status_if_free(server: Any) -> None:
    """The periodic status of an actionlib ActionServer, skipped while another thread holds the server's
    lock (a goal being accepted or finished publishes its status anyway): the periodic callbacks share
    one thread, which must not wait on a server."""
    if server.lock.acquire(blocking=False):
        try:
            server.publish_status_async(None)
        finally:
            server.lock.release()


class CallSiteThrottle:
    """Throttled logging keyed on the line of agent code that logs. rospy's *_throttle keys its period on
    the line that calls it, which through this backend is one line for every message: a frequent message
    (a task's progress every 2 s) silenced every other one of the same level (the clearance guard's
    vertical-speed line never printed). Time going back (a restarted simulation) lets a line log again."""

    def __init__(self, clock: Callable[[], float]) -> None:
        self._clock = clock
        self._last: dict[tuple[str, int], float] = {}

    def due(self, period: float, depth: int = 2) -> bool:
        """True if the caller `depth` frames up has not logged within `period` s (and records it)."""
        frame = sys._getframe(depth)
        key = (frame.f_code.co_filename, frame.f_lineno)
        now = self._clock()
        last = self._last.get(key)
        if last is not None and last <= now < last + period:
            return False
        self._last[key] = now
        return True


class RosBackend:
    """rospy implementation of the backend used by AgentInterface and Agent.

    Timers, sleeps and the action servers' periodic status run from the RosTimeScheduler (two threads,
    started with the first of them) instead of a thread each that rospy wakes on every /clock message."""

    def __init__(self):
        self._scheduler = None
        self._scheduler_lock = threading.Lock()
        self._throttle = CallSiteThrottle(rospy.get_time)

    def scheduler(self) -> RosTimeScheduler:
        """The agent's ROS-time scheduler (started on first use, after rospy.init_node)."""
        with self._scheduler_lock:
            if self._scheduler is None:
                self._scheduler = RosTimeScheduler(rospy.get_time, rospy.rostime.get_rostime_cond(),
                                                   rospy.is_shutdown,
                                                   lambda m: rospy.logerr_throttle(5.0, m)).start()
            return self._scheduler

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
        """A started actionlib SimpleActionServer whose periodic status comes from the scheduler every
        ACTION_STATUS_PERIOD (actionlib's own status timer, a thread per server, is stopped)."""
        server = actionlib.SimpleActionServer(name, action, execute_cb=execute_cb, auto_start=False)
        server.start()
        inner = getattr(server, 'action_server', None)
        status_timer = getattr(inner, 'status_timer', None)
        if status_timer is not None and hasattr(inner, 'publish_status_async') and hasattr(inner, 'lock'):
            status_timer.shutdown()
            self.scheduler().every(ACTION_STATUS_PERIOD, lambda _e, s=inner: _publish_status_if_free(s))
        return server

    def timer(self, period: float, callback: Callable[[Any], None]) -> Any:
        """A periodic callback on ROS time (sim time aware, like rospy.Timer; the callback gets None);
        the handle has shutdown()."""
        return self.scheduler().every(period, callback)

    def now(self) -> float:
        """Current ROS time in seconds (sim time when /use_sim_time)."""
        return rospy.get_time()

    def sleep(self, seconds: float) -> None:
        """Sleep `seconds` of ROS time; returns quietly on shutdown or when sim time jumps back, and after
        at most 2 x `seconds` + 1 s of wall time (never sooner than ROS time at a real-time factor >= 0.5).
        Why the wall bound: in simulation /clock comes from the ground station and stops when the robot's
        link is cut; a task asleep on it would never see the preempt of the heartbeat watchdog's safe stop
        (mbzirc_robustness fault suite, permanently cut UAV).
        Event-driven: the thread waits once, on an alarm of the scheduler, not in 10 ms polls."""
        seconds = max(float(seconds), 0.0)
        if seconds <= 0.0 or rospy.is_shutdown():
            return
        scheduler = self.scheduler()
        alarm = scheduler.alarm(rospy.get_time() + seconds)
        if not alarm.wait(2.0 * seconds + 1.0):
            scheduler.cancel(alarm)

    def start_thread(self, name: str, target: Callable[[], None]) -> threading.Thread:
        """A started daemon thread (the fake backend's threads take part in its simulated clock)."""
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        return thread

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
        if self._throttle.due(period):
            rospy.loginfo(msg)

    def logerr_throttle(self, period: float, msg: str) -> None:
        if self._throttle.due(period):
            rospy.logerr(msg)

    def logerr(self, msg: str) -> None:
        rospy.logerr(msg)

    def logwarn(self, msg: str) -> None:
        rospy.logwarn(msg)
