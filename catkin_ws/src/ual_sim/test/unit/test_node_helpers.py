"""Helpers of the ROS adapter that carry logic: output scheduling in sim time, yaw <-> quaternion."""
import math

import pytest

from ual_sim.node import Due, quat_yaw, yaw_quat


def test_due_holds_the_rate_on_average():
    due = Due(14.0)
    ticks = [k / 30.0 for k in range(1, 30 * 10 + 1)]       # 10 s of 30 Hz ticks
    n = sum(due(t) for t in ticks)
    assert n == pytest.approx(140, abs=1)


def test_due_does_not_burst_after_a_gap():
    due = Due(10.0)
    assert due(0.0)
    assert due(5.0)           # a long gap: one output, not fifty
    assert not due(5.01)


@pytest.mark.parametrize("yaw", [0.0, 0.5, -2.0, math.pi - 1e-3])
def test_yaw_quaternion_roundtrip(yaw):
    assert quat_yaw(yaw_quat(yaw)) == pytest.approx(yaw)
