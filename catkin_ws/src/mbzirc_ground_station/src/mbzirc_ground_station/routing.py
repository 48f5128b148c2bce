"""Which part of the ground station's state a topic feeds: one table, used live and in replay."""
from __future__ import annotations

import re
from typing import NamedTuple, Optional

__all__ = ["Route", "route", "ROBOT_TOPICS", "SHARED_TOPICS", "REPLAY_TOPIC_REGEX"]


class Route(NamedTuple):
    kind: str          # "data_feed", "action", "smach", or a shared kind below
    robot: str = ""    # robot id ("0" = UGV) for per-robot topics
    task: str = ""     # task name for action topics
    part: str = ""     # goal | feedback | result for action topics


# Per-robot topics, relative to /mbzirc2020_<id>/ (kind, name).
# data_feed carries pose, UAL state, water and blanket: one subscription per robot at 10 Hz.
ROBOT_TOPICS = {"data_feed": "data_feed", "smach/container_status": "smach"}
# Shared topics (kind by absolute name). /sim/score is the referee's ground truth (sim only).
SHARED_TOPICS = {"/estimated_objects": "fires", "/regions": "regions", "/central_unit/status": "cu_status",
                 "/central_unit/heartbeat": "cu_heartbeat", "/sim/score": "score", "/clock": "clock"}

_ROBOT = re.compile(r"^/mbzirc2020_(\d+)/(.+)$")
_ACTION = re.compile(r"^(\w+)_action/(goal|feedback|result)$")
# every topic the state reads, for `rosbag` filters (replay reads only these)
REPLAY_TOPIC_REGEX = re.compile(r"^(/mbzirc2020_\d+/(data_feed|smach/container_status|\w+_action/(goal|feedback|result))|"
                                + "|".join(re.escape(t) for t in SHARED_TOPICS) + r")$")


def route(topic: str) -> Optional[Route]:
    """The route of a topic name, or None when the ground station does not use it."""
    kind = SHARED_TOPICS.get(topic)
    if kind:
        return Route(kind)
    m = _ROBOT.match(topic)
    if not m:
        return None
    robot, rest = m.group(1), m.group(2)
    kind = ROBOT_TOPICS.get(rest)
    if kind:
        return Route(kind, robot)
    a = _ACTION.match(rest)
    if a:
        return Route("action", robot, a.group(1), a.group(2))
    return None
