"""RobotIO.publish with subscribers that come and go between its checks (no ROS master: rospy's
publishers, subscribers and services are replaced by fakes)."""
import types

import pytest
import rospy

from ual_sim import node as ual_node
from ual_sim.sim import Simulation
from ual_sim.uncertainty import profile
from ual_sim.world import load_world


class _CountingPublisher:
    """A publisher whose subscriber count follows a script, one value per get_num_connections call."""
    script: list = []

    def __init__(self, name, *_a, **_k):
        self.name, self.sent = name, []

    def get_num_connections(self):
        if self.name.endswith("ual/velocity") and _CountingPublisher.script:
            return _CountingPublisher.script.pop(0)
        return 0

    def publish(self, m):
        self.sent.append(m)


@pytest.fixture
def robot_io(monkeypatch):
    monkeypatch.setattr(rospy, "Publisher", _CountingPublisher)
    monkeypatch.setattr(rospy, "Subscriber", lambda *a, **k: None)
    monkeypatch.setattr(rospy, "Service", lambda *a, **k: None)
    world = load_world()
    sim = Simulation(world, seed=3, uncertainty=profile(world.uncertainty, "realistic"), wind=False)
    params = {"laser": False, "thermal": False, "rgbd": False, "pub_rate": 30.0, "laser_rate": 10.0,
              "thermal_rate": 8.0, "rgbd_rate": 5.0, "tf_odom": False}
    fake_node = types.SimpleNamespace(sim=sim, params=params, timed=lambda _n, fn: fn())
    r = sim.robots[2]
    return ual_node.RobotIO(fake_node, r, 0)


def test_a_velocity_subscriber_connecting_during_a_tick_gets_a_velocity(robot_io):
    """A subscriber that connects between the tick's first look at the velocity publisher and its publish
    (a robot's agent starting) gets a velocity message; before, the velocity was computed only when someone
    listened at the first look, and ual_sim died on None (realistic benchmark, seed 105 at start)."""
    _CountingPublisher.script = [0] + [1] * 10    # nobody at the first look, one subscriber from then on
    for now in (0.0, 0.1, 0.2):
        robot_io.publish(now, rospy.Time.from_sec(now))
    assert robot_io.pub_vel.sent, "no velocity published once a subscriber was there"
    assert all(abs(m.twist.linear.z) < 1.0 for m in robot_io.pub_vel.sent)
