"""Helpers of the ROS adapter that carry logic: output scheduling in sim time, yaw <-> quaternion."""
import math

import pytest

from ual_sim.node import AtMostPerWallSecond, Due, paced_origin, quat_yaw, yaw_quat


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


def test_clock_messages_at_most_rate_per_wall_second():
    """/clock of a simulator ticking 240 times a wall second (8x real time at 30 Hz), capped at 100."""
    wall = [0.0]
    due = AtMostPerWallSecond(100.0, clock=lambda: wall[0])
    sent = 0
    for _ in range(240):
        sent += due()
        wall[0] += 1.0 / 240.0
    assert 90 <= sent <= 100


def test_clock_every_tick_below_the_cap_or_without_one():
    wall = [0.0]
    capped, uncapped = AtMostPerWallSecond(100.0, clock=lambda: wall[0]), AtMostPerWallSecond(0.0)
    for _ in range(60):                     # 2x real time: 60 ticks a wall second
        assert capped() and uncapped()
        wall[0] += 1.0 / 60.0


@pytest.mark.parametrize("yaw", [0.0, 0.5, -2.0, math.pi - 1e-3])
def test_yaw_quaternion_roundtrip(yaw):
    assert quat_yaw(yaw_quat(yaw)) == pytest.approx(yaw)


def test_a_simulation_behind_its_real_time_factor_catches_up_at_most_the_limit_in_a_burst():
    """passage_realistic.test in a loaded CI run: 3.2 sim-s ran in 0.14 wall-s (a 1 s catch-up at 4x) while a
    UAV crossed a window, uncommanded, and it hit the frame. Behind by more than the limit, the pacing's origin
    moves so that the simulation is the limit behind; ahead or less behind, it stays."""
    assert paced_origin(100.0, 0.05, 0.1) == 100.0
    assert paced_origin(100.0, -0.08, 0.1) == 100.0
    wall0 = paced_origin(100.0, -0.8, 0.1)
    assert wall0 == pytest.approx(100.7)
    # what is left to catch up from there: 0.1 wall s (0.4 sim-s at 4x, under the 0.5 s velocity timeout)
    wall, sim_elapsed, rtf = 105.0, 4.0 * (105.0 - 100.0 - 0.8), 4.0
    assert sim_elapsed / rtf - (wall - wall0) == pytest.approx(-0.1)
