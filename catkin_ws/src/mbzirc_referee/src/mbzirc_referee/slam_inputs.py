"""The referee's ROS side of indoor SLAM: each robot's localization source and pose, the truth, the SLAM
maps, and the map files at the end (issue 18).

Subscribed per robot: `localization/source` and `localization/pose` (indoor_localization), `slam_out_pose`
(hector_mapping: paired by stamp with `localization/pose`, in whichever order they come, it gives the anchor arena <- `<ns>/map` without
reading /tf, which ual_sim fills at every tick); `/sim/robots` (truth, 2 Hz, in the order of `/sim/robot_ids`).
The maps are not subscribed (a 2048 x 2048 grid of 4 MB that hector_mapping would then build and send every
2 s per robot): each SLAM robot that has been indoors (or on `slam`) is asked for its map (`dynamic_map`,
nav_msgs/GetMap) every `fetch_period` sim seconds, once as it leaves SLAM (its source turns from `slam` to
another: out through the window) and once more at the end of the trial; on an interrupted trial (Ctrl+C: the
services may be gone) the last map fetched is written.

A map fetched while its robot is on SLAM, or as it leaves it, is that SLAM period's, kept with the robot's anchor
at that time: each floor's file merges the newest map of every such period on it (the floor of the indoor flight
the period belongs to). Why: indoor_pose starts a new SLAM map outside for every height band (its
`~map_height_band`), so a robot's newest map at the end of the trial may be its transit altitude's; and two
visits of one floor are two maps, in two frames.
"""
from __future__ import annotations

import math
import threading
from typing import Any, Callable, Optional

import rospy
from geometry_msgs.msg import PoseArray, PoseStamped
from mbzirc_ros_utils.periodic import PeriodicTimer
from nav_msgs.msg import OccupancyGrid
from nav_msgs.srv import GetMap, GetMapRequest, GetMapResponse
from rospy.numpy_msg import numpy_msg
from std_msgs.msg import String

from mbzirc_arena import messages as M
from mbzirc_arena.yaw import yaw_from_quaternion

from .indoor_flights import SlamRecord, anchor_from_pair
from .slam_maps import Grid, GridError, grid_from_message, map_entry, place, write_map_server

THROTTLE_S = 10.0
RECENT_SLAM_POSES = 20        # poses kept per robot and frame waiting for the other one of their stamp
PERIOD_SLACK = 1.0            # s: a SLAM period starts at most this long before its indoor flight (the fix is
                              # lost at the window, the truth is indoors a moment later)
__all__ = ["SlamInputs"]


class _NumpyGetMap:
    """nav_msgs/GetMap whose response's map data deserialises into a numpy array (4 M cells in ms)."""
    _type = GetMap._type
    _md5sum = GetMap._md5sum
    _request_class = GetMapRequest
    _response_class = numpy_msg(GetMapResponse)


def _pose(msg: PoseStamped) -> Optional[tuple]:
    """(t, x, y, z, yaw) of a pose message, None when not finite."""
    p, q = msg.pose.position, msg.pose.orientation
    yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
    out = (msg.header.stamp.to_sec(), p.x, p.y, p.z, yaw)
    return out if yaw is not None and all(math.isfinite(v) for v in out) else None


def grid_of(msg: OccupancyGrid) -> Grid:
    """The Grid of an OccupancyGrid message; GridError when malformed."""
    info, q = msg.info, msg.info.origin.orientation
    yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w) or 0.0     # an origin left unset is no rotation
    return grid_from_message(int(info.width), int(info.height), info.resolution,
                             (info.origin.position.x, info.origin.position.y, yaw), msg.data)


class SlamInputs:
    """Feeds `slam` (under `lock`) from the robots' SLAM topics and keeps their newest maps.

    Args:
        slam: the record's SLAM part.
        lock: the record's lock.
        robot_ids: robots to listen to (those without SLAM publish nothing: no cost).
        fetch_period: sim seconds between two map requests per robot (0: only at the end).
        arena_frame: the frame of the arena (a map already in it needs no anchor).
    """

    def __init__(self, slam: SlamRecord, lock: threading.Lock, robot_ids: list, fetch_period: float = 30.0,
                 arena_frame: str = "arena", on_truth: Optional[Callable[..., None]] = None) -> None:
        self.slam, self.lock, self.arena_frame = slam, lock, arena_frame
        self.on_truth = on_truth                           # (robot, t, x, y, z) of every true pose, lock held
        self.grids: dict[str, tuple] = {}                  # robot -> (Grid, frame)
        self.period_grids: dict[tuple, tuple] = {}         # (robot, SLAM period's start) -> (Grid, frame, anchor)
        self.recent: dict[tuple, dict[float, tuple]] = {}  # (robot, "map" | "arena") -> {stamp: (x, y, yaw)}
        self.truth_ids: Optional[list] = None
        self.anchor_t: dict[str, float] = {}               # robot -> stamp of its newest anchor
        self.fetch_lock = threading.Lock()
        self.subs = []
        for rid in robot_ids:
            ns = M.robot_ns(rid)
            self.subs += [rospy.Subscriber(f"/{ns}/localization/source", String, self._on_source, rid, queue_size=5),
                          rospy.Subscriber(f"/{ns}/localization/pose", PoseStamped, self._on_pose, rid, queue_size=5),
                          rospy.Subscriber(f"/{ns}/slam_out_pose", PoseStamped, self._on_slam_pose, rid,
                                           queue_size=5)]
        self.subs.append(rospy.Subscriber("/sim/robots", PoseArray, self._on_truth, queue_size=2))
        self.timer = PeriodicTimer(fetch_period, self.fetch_maps, "recorder SLAM maps") if fetch_period > 0 else None

    # ---- inputs ----------------------------------------------------------------------------------
    def _on_source(self, msg: String, robot: str) -> None:
        with self.lock:
            period = self._slam_period(robot)
            changed = self.slam.set_source(robot, rospy.get_time(), msg.data)
        if changed and period is not None:        # leaving SLAM: the period's map, before any new one
            threading.Thread(target=self.fetch_left_map, args=(robot, period), daemon=True,
                             name=f"recorder map of {robot}").start()

    def _slam_period(self, robot: str) -> Optional[float]:
        """The start of the robot's SLAM period when it is on SLAM now, else None. With the lock held."""
        changes = self.slam.sources.get(robot)
        return changes[-1][0] if changes and self.slam.on_slam(robot) else None

    def _on_slam_pose(self, msg: PoseStamped, robot: str) -> None:
        pose = _pose(msg)
        if pose is None:
            rospy.logwarn_throttle(THROTTLE_S, f"mission_recorder: non-finite slam_out_pose of robot {robot} ignored")
            return
        with self.lock:
            self._pair(robot, pose[0], "map", (pose[1], pose[2], pose[4]))

    def _on_pose(self, msg: PoseStamped, robot: str) -> None:
        pose = _pose(msg)
        if pose is None:
            rospy.logwarn_throttle(THROTTLE_S, f"mission_recorder: non-finite localization/pose of robot {robot} "
                                   "ignored")
            return
        t, x, y, z, yaw = pose
        with self.lock:
            self.slam.add_pose(robot, t, x, y, z)
            self._pair(robot, t, "arena", (x, y, yaw))

    def _pair(self, robot: str, t: float, frame: str, pose: tuple) -> None:
        """Keep a pose of `robot` at stamp t in `frame` ("map": slam_out_pose, "arena": localization/pose);
        with the other one of the same stamp (the SLAM pose a localization/pose was anchored from), whichever
        came first, it updates the robot's anchor. With the lock held."""
        other = self.recent.setdefault((robot, "arena" if frame == "map" else "map"), {}).pop(t, None)
        if other is None:
            recent = self.recent.setdefault((robot, frame), {})
            recent[t] = pose
            while len(recent) > RECENT_SLAM_POSES:
                del recent[min(recent)]
            return
        if t >= self.anchor_t.get(robot, -math.inf):
            in_arena, in_map = (pose, other) if frame == "arena" else (other, pose)
            self.slam.anchors[robot] = anchor_from_pair(in_arena, in_map)
            self.anchor_t[robot] = t

    def _on_truth(self, msg: PoseArray) -> None:
        if self.truth_ids is None:
            self.truth_ids = [str(i) for i in rospy.get_param("/sim/robot_ids", [])]
        if len(self.truth_ids) != len(msg.poses):
            rospy.logwarn_throttle(THROTTLE_S, f"mission_recorder: /sim/robots has {len(msg.poses)} poses, "
                                   f"/sim/robot_ids {len(self.truth_ids)}: ignored")
            self.truth_ids = None                      # read the ids again with the next message
            return
        t = msg.header.stamp.to_sec() or rospy.get_time()
        with self.lock:
            for rid, p in zip(self.truth_ids, msg.poses):
                xyz = (p.position.x, p.position.y, p.position.z)
                if all(math.isfinite(v) for v in xyz):
                    self.slam.add_truth(rid, t, *xyz)
                    if self.on_truth is not None:
                        self.on_truth(rid, t, *xyz)

    # ---- maps ------------------------------------------------------------------------------------
    def fetch_maps(self, _event: Any = None) -> None:
        """Ask every SLAM robot that has been indoors (or on slam) for its map; a malformed one is refused (throttled)."""
        with self.fetch_lock:
            with self.lock:
                robots = list(self.slam.been_inside)
            for robot in sorted(robots):
                self._fetch(robot)

    def fetch_left_map(self, robot: str, period: float) -> None:
        """fetch_maps for one robot that has just left the SLAM period started at `period` (see accept_map)."""
        with self.fetch_lock:
            self._fetch(robot, period)

    def _fetch(self, robot: str, period: Optional[float] = None) -> None:
        name = f"/{M.robot_ns(robot)}/dynamic_map"
        try:
            msg = rospy.ServiceProxy(name, _NumpyGetMap)().map
        except (rospy.ServiceException, rospy.ROSException) as e:
            rospy.logwarn_throttle(THROTTLE_S, f"mission_recorder: no map from {name}: {e}")
            return
        self.accept_map(robot, msg, period)

    def accept_map(self, robot: str, msg: OccupancyGrid, period: Optional[float] = None) -> bool:
        """Keep a robot's map if it is well formed; else a throttled warning. True when kept. A map of a robot on
        SLAM now (or of `period`, the start of the SLAM period it has just left) is also kept as that period's,
        with the robot's anchor now."""
        try:
            grid = grid_of(msg)
        except (GridError, ValueError, TypeError, AttributeError) as e:
            rospy.logwarn_throttle(THROTTLE_S, f"mission_recorder: malformed map of robot {robot} refused: {e}")
            return False
        frame = msg.header.frame_id.strip("/")
        with self.lock:
            self.grids[robot] = (grid, frame)
            period = self._slam_period(robot) if period is None else period
            if period is not None:
                self.period_grids[(robot, period)] = (grid, frame, self.slam.anchors.get(robot))
        return True

    def fetch_maps_within(self, timeout: float) -> None:
        """fetch_maps, waiting at most `timeout` wall seconds (a service call has no timeout of its own)."""
        worker = threading.Thread(target=self.fetch_maps, daemon=True)
        worker.start()
        worker.join(timeout)
        if worker.is_alive():
            rospy.logwarn(f"mission_recorder: the SLAM maps did not come within {timeout:.0f} s: the last ones "
                          "fetched are written")

    def write_maps(self, out_dir: str, t_end: float, floor_of: Callable[[float], int]) -> tuple:
        """Write map_floor<N>.pgm/.yaml for every floor mapped; (summary entries, {floor: ArenaMap})."""
        with self.lock:
            floors = self.slam.map_floors(t_end, floor_of)
            flights = self.slam.flights(t_end, floor_of)
            anchors = dict(self.slam.anchors)
            anchor_t = dict(self.anchor_t)
            grids = dict(self.grids)
            period_grids = dict(self.period_grids)
        by_floor: dict[int, list] = {}
        for (robot, start), (grid, frame, anchor) in sorted(period_grids.items()):
            floor = next((f["floor"] for f in flights if f["robot"] == robot
                          and f["t_start"] - PERIOD_SLACK <= start <= f["t_end"]), None)
            anchor = (0.0, 0.0, 0.0) if frame == self.arena_frame else anchor
            if floor is not None and anchor is not None:
                by_floor.setdefault(floor, []).append((robot, grid, anchor))
        for robot, floor in sorted(floors.items()):
            if any(r == robot for r, _ in period_grids):
                continue                          # its SLAM periods' maps are placed above
            grid, frame = grids.get(robot, (None, ""))
            anchor = (0.0, 0.0, 0.0) if frame == self.arena_frame else anchors.get(robot)
            if grid is None or anchor is None:
                rospy.logwarn(f"mission_recorder: robot {robot} flew indoors on floor {floor} but its "
                              f"{'map' if grid is None else 'anchor'} never came: not in map_floor{floor}")
                continue
            by_floor.setdefault(floor, []).append((robot, grid, anchor))
        entries, maps = [], {}
        for floor, items in sorted(by_floor.items()):
            m = place([(grid, anchor) for _, grid, anchor in items])
            if m is None:
                continue
            stem = f"map_floor{floor}"
            write_map_server(m, out_dir, stem)
            maps[floor] = m
            entry = map_entry(floor, sorted({robot for robot, _, _ in items}), stem, m)
            entry["anchors"] = {robot: {"pose": [round(v, 3) for v in anchor], "t": anchor_t.get(robot)}
                                for robot, _, anchor in items}      # where each grid was placed from
            entries.append(entry)
        return entries, maps

