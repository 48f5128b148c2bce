"""Replay of the committed short bag: the frame at any t equals folding the bag's messages up to t."""
import os

import pytest
import rosbag

from mbzirc_ground_station.bag_source import BagSource
from mbzirc_ground_station.replay import Replay
from mbzirc_ground_station.routing import route
from mbzirc_ground_station.state import GroundStationState

BAG = os.path.join(os.path.dirname(__file__), "..", "data", "short_mission.bag")


def folded(t):
    s = GroundStationState()
    with rosbag.Bag(BAG) as bag:
        for topic, msg, mt in bag.read_messages():
            if mt.to_sec() <= t and route(topic) is not None:
                s.apply(topic, msg, mt.to_sec())
    return s.frame(t, tracks=True)


def test_bag_reads_only_station_topics_and_shows_every_robot():
    src = BagSource(BAG)
    assert src.topics and all(route(t) is not None for t in src.topics)
    r = Replay(src, GroundStationState)
    r.seek(src.end)
    f = r.frame()
    assert [x["id"] for x in f["robots"]] == ["0", "1", "2", "3"] and f["fires"] and f["bad_messages"] == {}
    assert all(x["pose"] is not None for x in f["robots"])


@pytest.mark.parametrize("dts", [(10.0, 25.0, 3.0, 29.9)])
def test_frames_equal_the_fold(dts):
    src = BagSource(BAG)
    r = Replay(src, GroundStationState, checkpoint_every=5.0)
    for dt in dts:
        r.seek(src.start + dt)
        got = r.frame(tracks=True)
        got.pop("replay")
        assert got == folded(src.start + dt)
