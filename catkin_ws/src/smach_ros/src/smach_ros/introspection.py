"""IntrospectionServer / IntrospectionClient: publish a smach tree's structure and live status.

Topics. ``server_name`` is a ROS name resolved as given, as upstream: a relative name lands in the node's
namespace (``'intro'`` in node ``/ns/node`` -> ``/ns/intro/smach/...``), ``'~intro'`` is private to the
node (``/ns/node/intro/smach/...``), ``'/intro'`` is global.

* ``<server_name>/smach/container_structure`` (SmachContainerStructure): one per container, at start and
  every 2 s;
* ``<server_name>/smach/container_status`` (SmachContainerStatus): one per container on every start,
  transition and termination, and every 2 s; ``local_data`` is base64(pickle protocol 2) of the
  container's userdata dict (what every SMACH viewer reads);
* ``<server_name>/smach/container_init`` (SmachContainerInitialStatusCmd), subscribed: sets a container's
  initial state and userdata. ``local_data`` there may be a JSON object or base64 pickle; the pickle is
  read by a restricted unpickler that only accepts plain builtin data, unless the node's
  ``~smach_allow_unpickle`` param (or the ``allow_unpickle`` argument) is True, the upstream behaviour.
  The whole topic can be turned off: ``~smach_allow_init`` param / ``allow_init`` argument (default True,
  as upstream).

A debugger (breakpoints, pause/step, forced outcomes, a bounded userdata inspector) is offered under
``<server_name>/smach/debug/...`` when the ``~smach_allow_debug`` param (or ``allow_debug`` argument) is
True; see :mod:`smach_ros.debugger`. Default off.

Userdata keys can be left out of ``local_data`` (``exclude_keys`` argument, ``~smach_exclude_keys``
param); values that cannot be pickled, or that are too big, are summarised as text (upstream #18, #77).
"""
from __future__ import annotations

import json
import threading
import time
from typing import Any, Iterable, Optional

import rospy
from std_msgs.msg import Header, String
from smach_msgs.msg import SmachContainerInitialStatusCmd, SmachContainerStatus, SmachContainerStructure

import smach
from smach_ros.debugger import StateDebugger
from smach_ros.userdata_codec import DecodeError, contains_opaque, decode_local_data, encode_local_data

__all__ = ["IntrospectionServer", "IntrospectionClient", "ContainerProxy", "STATUS_TOPIC", "INIT_TOPIC",
           "STRUCTURE_TOPIC", "DEBUG_STATUS_TOPIC", "DEBUG_COMMAND_TOPIC", "child_path"]

STATUS_TOPIC = "/smach/container_status"
INIT_TOPIC = "/smach/container_init"
STRUCTURE_TOPIC = "/smach/container_structure"
DEBUG_STATUS_TOPIC = "/smach/debug/status"
DEBUG_COMMAND_TOPIC = "/smach/debug/command"
HEARTBEAT_S = 2.0  # wall seconds: the heartbeat also serves viewers that join late, whatever the clock


class ContainerProxy:
    """Publishes the structure and status of one container and applies init commands to it."""

    def __init__(self, server_name: str, container: smach.Container, path: str, structure_pub: rospy.Publisher,
                 status_pub: rospy.Publisher, allow_unpickle: bool = False, exclude_keys: Iterable[str] = ()) -> None:
        self._server_name = server_name
        self._container = container
        self._path = path
        self._structure_pub = structure_pub
        self._status_pub = status_pub
        self._allow_unpickle = allow_unpickle
        self._exclude_keys = tuple(exclude_keys)
        self._lock = threading.Lock()
        self._enabled = True
        container.register_start_cb(self._start_cb)
        container.register_transition_cb(self._transition_cb)
        container.register_termination_cb(self._termination_cb)

    @property
    def path(self) -> str:
        return self._path

    def structure_msg(self) -> SmachContainerStructure:
        internal_outcomes, outcomes_from, outcomes_to = [], [], []
        for outcome, from_label, to_label in self._container.get_internal_edges():
            internal_outcomes.append(str(outcome))
            outcomes_from.append(str(from_label))
            outcomes_to.append(str(to_label))
        return SmachContainerStructure(
            header=Header(stamp=rospy.Time.now()), path=self._path,
            children=[str(c) for c in self._container.get_children().keys()],
            internal_outcomes=internal_outcomes, outcomes_from=outcomes_from, outcomes_to=outcomes_to,
            container_outcomes=[str(o) for o in self._container.get_registered_outcomes()])

    def status_msg(self, info: str = "") -> SmachContainerStatus:
        ud = self._container.userdata
        with ud._lock:
            data = dict(ud._data)
        return SmachContainerStatus(
            header=Header(stamp=rospy.Time.now()), path=self._path,
            initial_states=[str(s) for s in self._container.get_initial_states()],
            active_states=[str(s) for s in self._container.get_active_states()],
            local_data=encode_local_data(data, self._exclude_keys), info=info)

    def publish_structure(self) -> None:
        if self._enabled:
            try:
                self._structure_pub.publish(self.structure_msg())
            except rospy.ROSException:
                pass

    def publish_status(self, info: str = "") -> None:
        """Publish this container's status. Never raises: it runs inside the machine's callbacks, and
        introspection must not stop a machine (upstream #77 did, on a userdata it could not pickle)."""
        if not self._enabled:
            return
        with self._lock:
            try:
                self._status_pub.publish(self.status_msg(info))
            except rospy.ROSException:
                pass
            except Exception as ex:  # noqa: BLE001 - a user container's getter, a message field
                rospy.logerr_throttle(5.0, "IntrospectionServer %s: status of %s not published: %r"
                                      % (self._server_name, self._path, ex))

    def _start_cb(self, ud: Any, initial_states: Any, *args: Any) -> None:
        self.publish_status("START")

    def _transition_cb(self, ud: Any, active_states: Any, *args: Any) -> None:
        self.publish_status("TRANSITION")

    def _termination_cb(self, ud: Any, terminal_states: Any, outcome: Any, *args: Any) -> None:
        self.publish_status("TERMINATED:%s" % outcome)

    def handle_init(self, msg: SmachContainerInitialStatusCmd) -> None:
        """Apply an init command addressed to this container; refuse bad ones with an error log."""
        children = self._container.get_children()
        unknown = [s for s in msg.initial_states if s not in children]
        if unknown:
            rospy.logerr_throttle(1.0, "Attempting to set initial state in container '%s' to %s, but this "
                                  "container only has states: %s" % (self._path, unknown, list(children)))
            return
        try:
            data = decode_local_data(msg.local_data, allow_unsafe=self._allow_unpickle)
        except DecodeError as ex:
            rospy.logerr_throttle(1.0, "Refused container_init for '%s': %s" % (self._path, ex))
            return
        if not self._allow_unpickle and contains_opaque(data):
            rospy.logerr_throttle(1.0, "Refused container_init for '%s': local_data holds objects of non-builtin "
                                  "classes; only plain data is accepted (set ~smach_allow_unpickle to trust "
                                  "pickles from the network)." % self._path)
            return
        ud = smach.UserData()
        ud._data = dict(data)
        try:
            self._container.set_initial_state(list(msg.initial_states), ud)
        except smach.InvalidStateError as ex:
            rospy.logerr_throttle(1.0, "Refused container_init for '%s': %s" % (self._path, ex))
            return
        self.publish_status("REMOTE_INIT")

    def stop(self) -> None:
        self._enabled = False


class IntrospectionServer:
    """Publishes the structure and status of a smach tree (every nested container) for viewers.

    Args:
        server_name: topic namespace, a ROS name resolved as given (relative: in the node's namespace, as
            upstream; '~name': private to the node).
        state: the root container.
        path: the root's path, e.g. '/SM_ROOT' ('/' alone gives children '/<label>'); children get
            '<path>/<label>'.
        allow_unpickle: trust pickles in container_init (default: the ``~smach_allow_unpickle`` param,
            False).
        allow_init: listen to container_init at all (default: the ``~smach_allow_init`` param, True).
        exclude_keys: userdata keys never sent in status messages nor shown by the debugger (default: the
            ``~smach_exclude_keys`` param, none).
        allow_debug: offer the debugger (default: the ``~smach_allow_debug`` param, False).
        breakpoints: state paths the debugger stops on from the start (with the ``~smach_debug_breakpoints``
            param and states marked by :func:`smach_ros.debugger.breakpoint_here`).
    """

    def __init__(self, server_name: str, state: smach.State, path: str,
                 allow_unpickle: Optional[bool] = None, allow_init: Optional[bool] = None,
                 exclude_keys: Optional[Iterable[str]] = None, allow_debug: Optional[bool] = None,
                 breakpoints: Iterable[str] = ()) -> None:
        self._server_name = server_name  # rospy resolves it (relative, '~' or global) when advertising
        self._state = state
        self._path = path
        self._allow_unpickle = allow_unpickle
        self._allow_init = allow_init
        self._exclude_keys = exclude_keys
        self._allow_debug = allow_debug
        self._breakpoints = list(breakpoints)
        self._debugger: Optional[StateDebugger] = None
        self._debug_pub: Optional[rospy.Publisher] = None
        self._debug_sub: Optional[rospy.Subscriber] = None
        self._proxies: list[ContainerProxy] = []
        self._keep_running = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self._structure_pub: Optional[rospy.Publisher] = None
        self._status_pub: Optional[rospy.Publisher] = None
        self._init_sub: Optional[rospy.Subscriber] = None

    def start(self) -> None:
        """Advertise the topics and start the 2 s heartbeat."""
        if self._allow_unpickle is None:
            self._allow_unpickle = bool(rospy.get_param("~smach_allow_unpickle", False))
        if self._allow_init is None:
            self._allow_init = bool(rospy.get_param("~smach_allow_init", True))
        if self._exclude_keys is None:
            self._exclude_keys = _param_list("~smach_exclude_keys")
        if self._allow_unpickle and self._allow_init:
            rospy.logwarn("IntrospectionServer %s trusts pickles from the network (smach_allow_unpickle)."
                          % self._server_name)
        self._structure_pub = rospy.Publisher(self._server_name + STRUCTURE_TOPIC, SmachContainerStructure,
                                              queue_size=50, latch=False)
        self._status_pub = rospy.Publisher(self._server_name + STATUS_TOPIC, SmachContainerStatus, queue_size=100)
        self._proxies = []
        self.construct(self._server_name, self._state, self._path)
        if self._allow_init:
            self._init_sub = rospy.Subscriber(self._server_name + INIT_TOPIC, SmachContainerInitialStatusCmd,
                                              self._init_cb, queue_size=10)
        self._start_debugger()
        self._keep_running.set()
        self._thread = threading.Thread(name=self._server_name + ":heartbeat", target=self._heartbeat, daemon=True)
        self._thread.start()

    def _start_debugger(self) -> None:
        """Offer the debugger if allowed; else say (latched) that it is not."""
        if self._allow_debug is None:
            self._allow_debug = bool(rospy.get_param("~smach_allow_debug", False))
        self._debug_pub = rospy.Publisher(self._server_name + DEBUG_STATUS_TOPIC, String, queue_size=10, latch=True)
        if not self._allow_debug:
            self._debug_pub.publish(String(data=json.dumps(
                {"allowed": False, "init_allowed": bool(self._allow_init),
                 "reason": "debugging is off on this server (~smach_allow_debug)"})))
            return
        rospy.logwarn("IntrospectionServer %s offers the SMACH debugger (smach_allow_debug): anyone on the ROS "
                      "network can pause this machine and force outcomes." % self._server_name)
        breakpoints = self._breakpoints + _param_list("~smach_debug_breakpoints")
        pub = self._debug_pub

        def publish(text: str) -> None:
            try:
                pub.publish(String(data=text))
            except rospy.ROSException:  # stopped or shutting down: nobody to tell
                pass

        debugger = self._debugger = StateDebugger(self._state, self._path, publish, breakpoints,
                                                  self._exclude_keys or (), is_shutdown=rospy.is_shutdown,
                                                  extra_status={"init_allowed": bool(self._allow_init)})
        debugger.install()
        self._debug_sub = rospy.Subscriber(self._server_name + DEBUG_COMMAND_TOPIC, String,
                                           lambda msg: debugger.handle_command(msg.data), queue_size=20)

    def construct(self, server_name: str, state: smach.State, path: str) -> None:
        """Create a proxy for ``state`` and, recursively, for every container below it."""
        if not isinstance(state, smach.Container):
            return
        proxy = ContainerProxy(server_name, state, path, self._structure_pub, self._status_pub,
                               bool(self._allow_unpickle), self._exclude_keys or ())
        self._proxies.append(proxy)
        for label, child in state.get_children().items():
            if isinstance(child, smach.Container):
                self.construct(server_name, child, child_path(path, label))

    def _init_cb(self, msg: SmachContainerInitialStatusCmd) -> None:
        for proxy in self._proxies:
            if proxy.path == msg.path:
                proxy.handle_init(msg)
                return
        rospy.logerr_throttle(1.0, "container_init for unknown path '%s' (known: %s)"
                              % (msg.path, [p.path for p in self._proxies]))

    def _heartbeat(self) -> None:
        while self._keep_running.is_set() and not rospy.is_shutdown():
            for proxy in list(self._proxies):
                proxy.publish_structure()
                proxy.publish_status("HEARTBEAT")
            deadline = time.monotonic() + HEARTBEAT_S
            while self._keep_running.is_set() and time.monotonic() < deadline and not rospy.is_shutdown():
                time.sleep(0.05)

    def stop(self) -> None:
        """Stop publishing and unadvertise the topics."""
        self._keep_running.clear()
        for proxy in self._proxies:
            proxy.stop()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(1.0)
        if self._debugger is not None:
            self._debugger.uninstall()
            self._debugger = None
        for handle in (self._init_sub, self._structure_pub, self._status_pub, self._debug_sub, self._debug_pub):
            if handle is not None:
                handle.unregister()
        self._init_sub = self._structure_pub = self._status_pub = self._debug_sub = self._debug_pub = None

    def clear(self) -> None:
        self.stop()


class IntrospectionClient:
    """Finds introspection servers and sends them init commands."""

    def get_servers(self) -> list:
        """Names of the servers publishing container status on the graph."""
        servers = []
        for topic, _type in rospy.get_published_topics():
            if topic.endswith(STATUS_TOPIC):
                servers.append(topic[: -len(STATUS_TOPIC)])
        return sorted(set(servers))

    def set_initial_state(self, server: str, path: str, initial_states: list,
                          initial_userdata: Optional[smach.UserData] = None,
                          timeout: Optional[rospy.Duration] = None) -> bool:
        """Ask ``server`` to set ``path``'s initial states (and userdata); with a timeout, wait until its
        status shows them and return whether it did."""
        data = dict(initial_userdata._data) if initial_userdata is not None else {}
        msg = SmachContainerInitialStatusCmd(path=path, initial_states=list(initial_states),
                                             local_data=encode_local_data(data))
        pub = rospy.Publisher(server + INIT_TOPIC, SmachContainerInitialStatusCmd, queue_size=1)
        try:
            if timeout is None:
                _wait_connections(pub, 2.0)
                pub.publish(msg)
                return True
            got = threading.Event()

            def status_cb(status: SmachContainerStatus) -> None:
                if status.path == path and all(s in status.initial_states for s in initial_states) \
                        and _holds(status.local_data, data):
                    got.set()

            sub = rospy.Subscriber(server + STATUS_TOPIC, SmachContainerStatus, status_cb)
            try:
                start = rospy.get_rostime()
                while not rospy.is_shutdown() and rospy.get_rostime() - start < timeout:
                    pub.publish(msg)
                    if got.wait(0.2):
                        return True
                return got.is_set()
            finally:
                sub.unregister()
        finally:
            pub.unregister()


def _param_list(name: str) -> list:
    """A list-of-names param (a single name is accepted as a list of one); anything else is refused with an
    error log and treated as empty."""
    value = rospy.get_param(name, [])
    if isinstance(value, str):
        return [value]
    if isinstance(value, list):
        return [str(v) for v in value]
    rospy.logerr("IntrospectionServer: param %s must be a list of names, got %r; ignored" % (name, value))
    return []


def child_path(path: str, label: str) -> str:
    """The path of child ``label`` of the container at ``path`` (the root may be '/')."""
    return path.rstrip("/") + "/" + label


def _holds(local_data: str, expected: dict) -> bool:
    """Whether a status's userdata has every key of ``expected`` with an equal value (read safely)."""
    if not expected:
        return True
    try:
        data = decode_local_data(local_data)
    except DecodeError:
        return False
    return all(key in data and data[key] == value for key, value in expected.items())


def _wait_connections(pub: rospy.Publisher, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while pub.get_num_connections() == 0 and time.monotonic() < deadline and not rospy.is_shutdown():
        time.sleep(0.02)
