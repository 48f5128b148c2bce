"""ROS side of the SLAM floor maps: reads each robot's occupancy grid, anchors it in the arena frame.

Subscribed only when a map topic appears (`/mbzirc2020_<id>/map`, nav_msgs/OccupancyGrid, latched by
hector_mapping), so a trial without indoor SLAM costs nothing; the TF listener is made with the first map
(it reads every /tf message). A grid is looked at only every `FloorMaps.min_period` seconds per robot.
"""
from __future__ import annotations

import re
import threading
import time
from typing import Any, Callable, Optional

import rospy
from mbzirc_arena.arena import floor_of
from mbzirc_arena.yaw import yaw_from_quaternion

from .floor_maps import FloorMaps, GridError, compact_grid, compose
from .live import LiveSource
from .state import robot_name

__all__ = ["MapListener", "MAP_TOPIC", "map_robot"]

MAP_TOPIC = re.compile(r"^/mbzirc2020_(\d+)/map$")
MAP_TYPE = "nav_msgs/OccupancyGrid"

# arena -> frame as (x, y, yaw), or None when not known yet
Lookup = Callable[[str, str], Optional[tuple]]
LOG_EVERY_S = 10.0   # wall seconds between two log lines of one kind per robot


def map_robot(topic: str) -> Optional[str]:
    """The robot id of a SLAM map topic, None for any other topic."""
    m = MAP_TOPIC.match(topic)
    return m.group(1) if m else None


def _yaw(q: Any) -> float:
    """Yaw of a message's quaternion; an all-zero one (an origin left unset) is no rotation."""
    return yaw_from_quaternion(q.x, q.y, q.z, q.w) or 0.0


def tf_lookup() -> Lookup:
    """A Lookup on a tf2 buffer (made here: call it only once a map exists)."""
    import tf2_ros
    buffer = tf2_ros.Buffer(cache_time=rospy.Duration(30.0))
    listener = tf2_ros.TransformListener(buffer)

    def lookup(parent: str, child: str) -> Optional[tuple]:
        _ = listener   # kept alive with the lookup
        try:
            t = buffer.lookup_transform(parent, child, rospy.Time(0)).transform
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException):
            return None
        return (t.translation.x, t.translation.y, _yaw(t.rotation))
    return lookup


class MapListener:
    """Feeds FloorMaps from the robots' grids.

    Args:
        live: the live state (the robot's height at the map's arrival gives the floor label).
        maps: where the compact maps go.
        arena_frame: the arena's frame id; a grid already in it is drawn at its own origin.
        make_lookup: makes the TF Lookup, called with the first grid that needs it.
        clock: seconds (sim time in the mission) for the rate limit.
        log: (level "warn" | "error", text), called at most every LOG_EVERY_S per kind and robot.
    """

    def __init__(self, live: LiveSource, maps: FloorMaps, arena_frame: str = "arena",
                 make_lookup: Callable[[], Lookup] = tf_lookup,
                 clock: Callable[[], float] = lambda: rospy.get_rostime().to_sec(),
                 log: Optional[Callable[[str, str], None]] = None) -> None:
        self.live = live
        self.maps = maps
        self.arena_frame = arena_frame.strip("/")
        self.make_lookup = make_lookup
        self.lookup: Optional[Lookup] = None
        self._lookup_lock = threading.Lock()   # the grids' callbacks run in one thread per topic
        self.clock = clock
        self.subs: dict[str, Any] = {}
        self.log = log or (lambda level, text: (rospy.logerr if level == "error" else rospy.logwarn)(text))
        self._logged_at: dict[tuple, float] = {}

    def _throttled(self, level: str, robot: str, text: str) -> None:
        now = time.monotonic()
        if now - self._logged_at.get((level, robot), -LOG_EVERY_S) >= LOG_EVERY_S:
            self._logged_at[(level, robot)] = now
            self.log(level, "ground station: " + text)

    def on_topics(self, topics: list) -> None:
        """Subscribe the map topics among the master's (name, type) pairs that are new."""
        for name, type_name in topics:
            robot = map_robot(name)
            if robot is None or name in self.subs or type_name != MAP_TYPE:
                continue
            from nav_msgs.msg import OccupancyGrid
            from rospy.numpy_msg import numpy_msg
            # numpy_msg: the 4 M cells of hector's grid arrive as one int8 array (5 ms), not a tuple of
            # Python ints (25 ms to unpack and 150 ms to turn back into an array, for every map of 3 robots)
            self.subs[name] = rospy.Subscriber(name, numpy_msg(OccupancyGrid), lambda m, r=robot: self.handle(r, m),
                                               queue_size=1, buff_size=1 << 24)

    def stop(self) -> None:
        for s in self.subs.values():
            s.unregister()

    def _anchor(self, frame: str) -> Optional[tuple]:
        if frame == self.arena_frame:
            return (0.0, 0.0, 0.0)
        with self._lookup_lock:
            if self.lookup is None:
                self.lookup = self.make_lookup()
        return self.lookup(self.arena_frame, frame)

    def _floor(self, robot: str) -> Optional[int]:
        with self.live.lock:
            view = self.live.state.robots.get(robot)
            pose = view.pose if view is not None else None
            floors = self.live.state.floor_heights
        return None if pose is None else floor_of(pose["z"], floors)

    def handle(self, robot: str, msg: Any) -> bool:
        """One grid of `robot`; True when the page's maps changed. Bad grids are logged and ignored."""
        now = self.clock()
        if not self.maps.admit(robot, now):
            return False
        frame = msg.header.frame_id.strip("/")
        try:
            info = msg.info
            grid = compact_grid(int(info.width), int(info.height), float(info.resolution), msg.data)
            anchor = self._anchor(frame)
            if anchor is None:
                self._throttled("warn", robot, "no transform %s -> %s yet: map of robot %s not drawn"
                                % (self.arena_frame, frame, robot))
                return False
            o = info.origin
            origin = compose(anchor, (o.position.x, o.position.y, _yaw(o.orientation)))
            entry = dict(grid, name=robot_name(robot))
            return self.maps.update(robot, entry, origin, self._floor(robot), frame, now)
        except (GridError, ValueError, TypeError, AttributeError) as ex:
            self._throttled("error", robot, "malformed map of robot %s ignored: %s" % (robot, ex))
            return False
