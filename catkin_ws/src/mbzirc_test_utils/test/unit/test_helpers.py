"""The shared rostest helpers without a ROS master: rospy.Subscriber, rosgraph.Master and Popen faked."""
import threading
import time

import pytest

from mbzirc_test_utils import bag_replay, collector
from mbzirc_test_utils.collector import Collector, agent_id


@pytest.fixture
def fake_subscriber(monkeypatch):
    made = []

    class Sub:
        def __init__(self, topic, cls, cb, queue_size=None):
            self.topic, self.cb = topic, cb
            made.append(self)

    monkeypatch.setattr(collector.rospy, "Subscriber", Sub)
    return made


def test_agent_id_of_namespaces():
    assert agent_id("/mbzirc2020_2/") == "2"
    assert agent_id("mbzirc2020_0") == "0"


def test_collector_counts_waits_and_keeps(fake_subscriber):
    c = Collector("sensed_objects", object)
    frames = Collector("camera/image", object, keep=False)
    assert c.last_time() is None and not c.wait(1, 0.1)
    threading.Timer(0.2, lambda: [fake_subscriber[0].cb(i) for i in range(3)]).start()
    assert c.wait(3, 5.0) and c.msgs == [0, 1, 2]
    fake_subscriber[1].cb("image")
    assert frames.count() == 1 and frames.msgs == [] and frames.last_time() <= time.time()


def test_wait_for_replay_ends_after_quiet_time(fake_subscriber):
    frames = Collector("t", object, keep=False)
    assert not bag_replay.wait_for_replay(frames, timeout=0.3)  # never played

    def play():
        for _ in range(5):
            frames.cb(None)
            time.sleep(0.1)

    t0 = time.time()
    threading.Thread(target=play).start()
    assert bag_replay.wait_for_replay(frames, timeout=10.0, quiet=0.5)
    assert frames.count() == 5 and time.time() - frames.last_time() >= 0.5
    assert time.time() - t0 < 3.0


def test_player_starts_once_the_node_subscribed(monkeypatch):
    calls = {"state": 0}
    started = []

    class Master:
        def __init__(self, name):
            pass

        def getSystemState(self):
            calls["state"] += 1
            subs = [["/mbzirc2020_1/scan", ["/mbzirc2020_1/fire_detector"]]]
            if calls["state"] >= 3:
                subs.append(["/mbzirc2020_1/teraranger_evo_thermal/raw_temp_array", ["/mbzirc2020_1/fire_detector"]])
            return [], subs, []

    monkeypatch.setattr(bag_replay.rosgraph, "Master", Master)
    monkeypatch.setattr(bag_replay.subprocess, "Popen", lambda cmd: started.append((calls["state"], cmd)) or cmd)
    bag_replay.play_bag_when_subscribed("x.bag", "/fire_detector", "teraranger_evo_thermal/raw_temp_array", 10.0)
    assert started == [(3, ["rosbag", "play", "--clock", "-q", "x.bag"])]


def test_bag_case_reads_the_param_and_bags_yaml(monkeypatch, tmp_path):
    data = tmp_path / "test" / "data"
    data.mkdir(parents=True)
    (data / "bags.yaml").write_text("a.bag: {ns: mbzirc2020_2, fire: [1.0, 2.0, 3.0]}\nb.bag: {ns: x, fire: null}\n")

    class Pack:
        def get_path(self, pkg):
            assert pkg == "fire_detector"
            return str(tmp_path)

    monkeypatch.setattr(bag_replay.rospy, "get_param", lambda name: {"~bag": "a.bag"}[name])
    monkeypatch.setattr(bag_replay.rospkg, "RosPack", Pack)
    path, name, truth = bag_replay.bag_case("fire_detector")
    assert (path, name) == (str(data / "a.bag"), "a.bag")
    assert truth == {"ns": "mbzirc2020_2", "fire": [1.0, 2.0, 3.0]}
