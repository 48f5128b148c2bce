"""ROS side of the live ground station: finds the topics it reads, subscribes, calls the command services.

Topics are found on the master every `discovery_period` wall seconds (never per frame); each one the
routing table knows is subscribed with its own message class, so every agent task's action goal, feedback
and result is read without a list of action types here.
"""
from __future__ import annotations

import threading
from typing import Any, Callable, Optional

import roslib.message
import rospy

from .commands import SERVICES, Command
from .live import LiveSource
from .routing import route

__all__ = ["TopicWatcher", "CommandRunner"]


class TopicWatcher:
    """Subscribes every published topic that the state reads, as it appears."""

    def __init__(self, live: LiveSource, period: float = 2.0,
                 on_topics: Optional[Callable[[list], None]] = None) -> None:
        self.live = live
        self.period = period
        self.on_topics = on_topics   # also given every topic list (the SLAM maps' own subscriber)
        self.subs: dict[str, Any] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="gcs_discovery", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        for s in self.subs.values():
            s.unregister()

    def discover(self) -> None:
        try:
            topics = rospy.get_published_topics()
        except Exception as ex:  # noqa: BLE001 - master gone: try again later
            rospy.logwarn_throttle(30, "ground station: cannot list topics: %s" % ex)
            return
        if self.on_topics is not None:
            self.on_topics(topics)
        for name, type_name in topics:
            if name in self.subs or route(name) is None:
                continue
            cls = roslib.message.get_message_class(type_name)
            if cls is None:
                rospy.logwarn_throttle(30, "ground station: unknown message type %s of %s" % (type_name, name))
                continue
            self.subs[name] = rospy.Subscriber(name, cls, self._callback(name), queue_size=20)

    def _callback(self, topic: str):
        def cb(msg: Any) -> None:
            self.live.apply(topic, msg)
        return cb

    def _loop(self) -> None:
        while not self._stop.is_set() and not rospy.is_shutdown():
            self.discover()
            self._stop.wait(self.period)


class CommandRunner:
    """Turns a Command into service calls (see commands.SERVICES); returns (ok, message)."""

    def __init__(self, live: LiveSource, timeout: float = 3.0) -> None:
        self.live = live
        self.timeout = timeout

    def _call(self, name: str, srv_type: Any, *args: Any) -> tuple[bool, str]:
        try:
            rospy.wait_for_service(name, self.timeout)
            resp = rospy.ServiceProxy(name, srv_type)(*args)
        except (rospy.ROSException, rospy.ServiceException) as ex:
            return False, "%s: %s" % (name, ex)
        return bool(resp.success), "%s: %s" % (name, resp.message) if resp.message else name

    def _robots(self, robot: str, uavs_only: bool = False) -> list[str]:
        with self.live.lock:
            views = dict(self.live.state.robots)
        ids = sorted(views) if robot == "all" else [robot]
        return [r for r in ids if not uavs_only or views[r].kind == "uav"]

    def __call__(self, cmd: Command) -> tuple[bool, str]:
        from std_srvs.srv import SetBool, Trigger
        if cmd.name == "start_trial":
            return self._call(SERVICES["start_trial"], Trigger)
        if cmd.name in ("pause", "resume"):
            return self._call(SERVICES["pause"], SetBool, cmd.name == "pause")
        results = []
        if cmd.name in ("send_home", "release"):     # per robot, or every robot known
            results = [self._call(SERVICES[cmd.name] % r, Trigger) for r in self._robots(cmd.robot)]
        elif cmd.name == "land_all":
            results = [self._call(SERVICES["pause"], SetBool, True)]
            results += [self._call(SERVICES["land"] % r, Trigger) for r in self._robots("all", uavs_only=True)]
        ok = bool(results) and all(ok for ok, _ in results)
        return ok, "; ".join(m for _, m in results) or "no robot"
