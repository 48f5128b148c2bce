"""Replaying a recorded rosbag into the node under test (`rosbag play --clock`).

Playing starts only once the node has subscribed (instead of after a fixed delay), which keeps the
tests independent of how slowly nodes start on a loaded machine.
"""
from __future__ import annotations

import os
import subprocess
import time

import rosgraph
import rospkg
import rospy
import yaml


def bag_case(pkg: str) -> tuple:
    """(path, name, truth) of the bag named by the test's `~bag` param: a file of <pkg>/test/data, and
    its entry in that folder's bags.yaml (what was true when it was recorded: namespace, positions)."""
    name = rospy.get_param("~bag")
    data = os.path.join(rospkg.RosPack().get_path(pkg), "test", "data")
    with open(os.path.join(data, "bags.yaml")) as f:
        truth = yaml.safe_load(f)[name]
    return os.path.join(data, name), name, truth


def play_bag_when_subscribed(path: str, node_suffix: str, topic_suffix: str,
                             timeout: float = 90.0) -> subprocess.Popen:
    """Starts `rosbag play --clock` once a node named *node_suffix subscribes to *topic_suffix.

    After `timeout` s without that subscription it plays anyway (the test then fails on what the node
    did not publish, with the node's own log to explain why). Returns the player process.
    """
    master = rosgraph.Master("/test_bag_player")
    end = time.time() + timeout
    while time.time() < end:
        _, subs, _ = master.getSystemState()
        if any(t.endswith(topic_suffix) and any(n.endswith(node_suffix) for n in nodes) for t, nodes in subs):
            break
        time.sleep(0.2)
    time.sleep(0.5)
    return subprocess.Popen(["rosbag", "play", "--clock", "-q", path])


def stop(player: subprocess.Popen) -> None:
    """Ends the player if it is still running (it may linger after the last message)."""
    try:
        player.wait(5)
    except subprocess.TimeoutExpired:
        player.terminate()
        player.wait(10)


def wait_for_replay(frames, timeout: float = 90.0, quiet: float = 3.0) -> bool:
    """Waits for the replay to start and to end: the first message of `frames` (a Collector of a topic
    the bag holds), then `quiet` s without one. False when the bag never played within `timeout` s;
    True also when it was still playing at the deadline (the test's counts then tell)."""
    end = time.time() + timeout
    while time.time() < end and frames.last_time() is None:
        time.sleep(0.1)
    if frames.last_time() is None:
        return False
    while time.time() < end and time.time() - frames.last_time() < quiet:
        time.sleep(0.1)
    return True
