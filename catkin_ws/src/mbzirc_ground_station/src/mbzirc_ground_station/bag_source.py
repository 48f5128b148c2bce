"""A rosbag as a replay MessageSource: only the topics the ground station reads, in time order.

Messages are read from the bag as the timeline reaches them (the bag's index makes a seek cheap), so a
long trial is never held in memory. Stamps are the bag's receive times: the recorder runs on sim time.
"""
from __future__ import annotations

from typing import Any, Iterator, Optional

import rosbag
import rospy

from .replay import Replay
from .routing import REPLAY_TOPIC_REGEX
from .state import GroundStationState

__all__ = ["BagSource", "open_bag_replay"]


class BagSource:
    """MessageSource over a bag file (see replay.MessageSource)."""

    def __init__(self, path: str) -> None:
        self.bag = rosbag.Bag(path, "r")
        info = self.bag.get_type_and_topic_info().topics
        self.topics = sorted(t for t in info if REPLAY_TOPIC_REGEX.match(t) and t != "/clock")
        self.start = self.bag.get_start_time()
        self.end = self.bag.get_end_time()

    def messages(self, after: float) -> Iterator[tuple[str, Any, float]]:
        start = rospy.Time.from_sec(max(0.0, after))
        for topic, msg, t in self.bag.read_messages(topics=self.topics, start_time=start):
            ts = t.to_sec()
            if ts > after:
                yield topic, msg, ts

    def close(self) -> None:
        self.bag.close()


def open_bag_replay(path: str, arena: Optional[dict], name: str) -> tuple[Replay, dict]:
    """A paused Replay of the bag at `path` and the page's info for it (`name`: how the page names it).
    Raises what rosbag raises for a file it cannot read."""
    replay = Replay(BagSource(path), lambda: GroundStationState(arena))
    info = {"mode": "replay", "arena": arena, "bag": name, "smach_viewer_port": 0, "commands": {}}
    return replay, info
