"""ROS side of the viewer: finds introspection servers on the graph, feeds the model, sends init commands."""
from __future__ import annotations

import json
import threading
from typing import Optional

import rospy
from smach_msgs.msg import SmachContainerInitialStatusCmd, SmachContainerStatus, SmachContainerStructure
from std_msgs.msg import String

from smach_ros.debugger import COMMANDS
from smach_ros.introspection import DEBUG_COMMAND_TOPIC, DEBUG_STATUS_TOPIC
from smach_ros.userdata_codec import encode_local_data
from smach_viewer.model import ViewerModel

__all__ = ["IntrospectionWatcher"]

STATUS_SUFFIX = "/smach/container_status"
STRUCTURE_SUFFIX = "/smach/container_structure"
INIT_SUFFIX = "/smach/container_init"


class IntrospectionWatcher:
    """Polls the master for ``*/smach/container_status`` topics and subscribes to each server's topics."""

    def __init__(self, model: ViewerModel, discovery_period: float = 1.0) -> None:
        self._model = model
        self._period = discovery_period
        self._subs: dict[str, tuple] = {}
        self._init_pubs: dict[str, rospy.Publisher] = {}
        self._debug_pubs: dict[str, rospy.Publisher] = {}
        self._lock = threading.Lock()
        self._timer: Optional[rospy.Timer] = None
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None

    def start(self) -> None:
        self.discover()
        self._thread = threading.Thread(target=self._loop, name="smach_viewer_discovery", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()

    def _loop(self) -> None:
        # wall-clock polling: discovery must work with a paused sim clock too
        while not self._stop.wait(self._period) and not rospy.is_shutdown():
            self.discover()

    def discover(self) -> None:
        try:
            topics = rospy.get_published_topics()
        except Exception as ex:  # noqa: BLE001 - master unreachable, keep trying
            rospy.logerr_throttle(10.0, "web_viewer: cannot list topics: %s" % ex)
            return
        servers = {t[: -len(STATUS_SUFFIX)] for t, ty in topics
                   if t.endswith(STATUS_SUFFIX) and ty == "smach_msgs/SmachContainerStatus"}
        with self._lock:
            for server in servers - set(self._subs):
                rospy.loginfo("web_viewer: found introspection server %s" % server)
                self._subs[server] = (
                    rospy.Subscriber(server + STRUCTURE_SUFFIX, SmachContainerStructure, self._on_structure,
                                     callback_args=server, queue_size=50),
                    rospy.Subscriber(server + STATUS_SUFFIX, SmachContainerStatus, self._on_status,
                                     callback_args=server, queue_size=100),
                    rospy.Subscriber(server + DEBUG_STATUS_TOPIC, String, self._on_debug, callback_args=server,
                                     queue_size=20))
            for server in set(self._subs) - servers:
                rospy.loginfo("web_viewer: introspection server %s is gone" % server)
                for sub in self._subs.pop(server):
                    sub.unregister()
                for pubs in (self._init_pubs, self._debug_pubs):
                    pub = pubs.pop(server, None)
                    if pub is not None:
                        pub.unregister()
                self._model.remove_server(server)

    def _on_structure(self, msg: SmachContainerStructure, server: str) -> None:
        try:
            self._model.update_structure(server, msg.path, list(msg.children), list(msg.internal_outcomes),
                                         list(msg.outcomes_from), list(msg.outcomes_to), list(msg.container_outcomes))
        except ValueError as ex:
            rospy.logerr_throttle(5.0, "web_viewer: bad structure message from %s: %s" % (server, ex))

    def _on_status(self, msg: SmachContainerStatus, server: str) -> None:
        try:
            self._model.update_status(server, msg.path, list(msg.initial_states), list(msg.active_states),
                                      msg.local_data, msg.info)
        except ValueError as ex:
            rospy.logerr_throttle(5.0, "web_viewer: bad status message from %s: %s" % (server, ex))

    def _on_debug(self, msg: String, server: str) -> None:
        try:
            self._model.update_debug(server, msg.data)
        except ValueError as ex:
            rospy.logerr_throttle(5.0, "web_viewer: bad debug status from %s: %s" % (server, ex))

    def send_debug(self, server: str, command: dict) -> str:
        """Send a debugger command (see smach_ros.debugger); returns an error text, or "" when sent."""
        debug = self._model.debug(server)
        if debug is None:
            return "server %r offers no debugger" % server
        if not debug.get("allowed"):
            return "debugging is not allowed on %s (~smach_allow_debug)" % server
        if command.get("cmd") not in COMMANDS:
            return "unknown command %r" % command.get("cmd")
        with self._lock:
            pub = self._debug_pubs.get(server)
            if pub is None:
                pub = self._debug_pubs[server] = rospy.Publisher(server + DEBUG_COMMAND_TOPIC, String, queue_size=20)
        threading.Thread(target=self._publish_when_connected, args=(pub, String(data=json.dumps(command))),
                         daemon=True).start()
        return ""

    def set_initial_state(self, server: str, path: str, state: str) -> str:
        """Send an init command; returns an error text, or "" when sent.

        ``local_data`` is a base64 pickle of an empty dict: every server (ours or upstream) accepts it and
        keeps its userdata as it is.
        """
        snap = self._model.snapshot()["servers"].get(server)
        if snap is None:
            return "unknown server %r" % server
        container = snap["containers"].get(path)
        if container is None:
            return "unknown container %r on %s" % (path, server)
        if container["has_structure"] and state not in container["children"]:
            return "%r is not a child of %s" % (state, path)
        if (snap.get("debug") or {}).get("init_allowed") is False:
            return "%s does not accept container_init (its node's ~smach_allow_init is false)" % server
        with self._lock:
            pub = self._init_pubs.get(server)
            if pub is None:
                pub = self._init_pubs[server] = rospy.Publisher(server + INIT_SUFFIX, SmachContainerInitialStatusCmd,
                                                                queue_size=10)
        msg = SmachContainerInitialStatusCmd(path=path, initial_states=[state], local_data=encode_local_data({}))
        threading.Thread(target=self._publish_when_connected, args=(pub, msg), daemon=True).start()
        return ""

    @staticmethod
    def _publish_when_connected(pub: rospy.Publisher, msg: object) -> None:
        import time
        deadline = time.monotonic() + 3.0
        while pub.get_num_connections() == 0 and time.monotonic() < deadline and not rospy.is_shutdown():
            time.sleep(0.02)
        pub.publish(msg)
