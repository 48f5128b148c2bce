"""The boxes a UAV reserves allow for the error of its reported pose (pose_error_boxes.py).

Realistic seed 107, t 384 s: UAV 3 hovered above the end of UAV 2's go-to leg, its hold box just clear of the
leg's box; UAV 2 was really 0.9 m higher and UAV 3 0.8 m lower than they reported, 0.83 m apart.
"""
import numpy as np
import pytest
from mbzirc_comm_objs.msg import GoToGoal, TakeOffGoal

from fake_backend import FakeBackend
from fake_ual import goal_pose, start_uav, stop_agent
from mbzirc_agents import constants as C
from mbzirc_agents.params import AgentParams
from mbzirc_agents.pose_error_boxes import GROUND_ANCHORED, grown, pose_error_pad


@pytest.fixture
def uav():
    be = FakeBackend()
    agent, ual = start_uav(be, {'region_timeout': 10.0}, speedup=8.0)
    yield agent, ual, be
    stop_agent(agent, ual, be)


def take_off(be, height):
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=height))
    return s.wait(30)


def lowest_granted_z(rm, agent_id, x, y, z0):
    """The lowest hover height over (x, y), from z0 up in 5 cm steps, at which a UAV under the same rules
    (hold box grown by the default pose error) is granted its hold box."""
    pad = pose_error_pad('hold', C.POSE_ERROR_MARGIN, C.POSE_ERROR_MARGIN_Z)
    h = C.HOLD_HALF_SIZE
    for z in np.arange(z0, z0 + 10.0, 0.05):
        lo, hi = grown((np.array([x - h, y - h, z - h]), np.array([x + h, y + h, z + h])), pad)
        if rm.ask(agent_id, 'hold', lo, hi)[0]:
            return float(z)
    raise AssertionError('never granted')


def test_hover_box_grows_by_the_pose_error_margins(uav):
    agent, ual, be = uav
    assert take_off(be, 6.0) == 'succeeded'
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(3.0, 0.0, 6.0, 0.0)))
    assert s.wait(20) == 'succeeded'
    lo, hi = ual.regions.regions()[('2', 'hold')]
    p = agent.position()[:3]
    reach_lo, reach_hi = p - np.asarray(lo), np.asarray(hi) - p
    want = C.HOLD_HALF_SIZE + np.array([C.POSE_ERROR_MARGIN, C.POSE_ERROR_MARGIN, C.POSE_ERROR_MARGIN_Z])
    assert reach_lo == pytest.approx(want, abs=1e-6) and reach_hi == pytest.approx(want, abs=1e-6)


def test_a_uav_above_another_stays_clear_of_it_with_both_heights_off_as_in_seed_107(uav):
    """UAV 2 (under test) arrives at z 6 and hovers; UAV 3 hovers right above as low as the manager lets
    it. With each reported height off by the margin the other way, the true UAVs stay as far apart as the
    ideal world keeps them (2 m); with seed 107's errors (+0.9 m, -0.8 m) more than 1.2 m (0.3 m before)."""
    agent, ual, be = uav
    assert take_off(be, 6.0) == 'succeeded'
    z2 = agent.position()[2]
    z3 = lowest_granted_z(ual.regions, '3', 0.0, 0.0, z2)
    reported_gap = z3 - z2
    assert reported_gap - 2 * C.POSE_ERROR_MARGIN_Z >= 2 * C.HOLD_HALF_SIZE - 1e-6
    assert reported_gap - (0.9 + 0.8) > 1.2


def test_two_go_to_legs_side_by_side_keep_the_true_uavs_apart_with_opposite_horizontal_errors(uav):
    """UAV 3 holds a box east of UAV 2's leg; the leg is granted only when the reported tracks keep apart
    by the boxes' margins plus both UAVs' horizontal errors."""
    agent, ual, be = uav
    assert take_off(be, 6.0) == 'succeeded'
    h = C.HOLD_HALF_SIZE
    pad = pose_error_pad('hold', C.POSE_ERROR_MARGIN, C.POSE_ERROR_MARGIN_Z)
    x3 = 2 * h + 2 * C.POSE_ERROR_MARGIN - 0.1      # the leg (along y at x 0) needs x3 >= 2 h + 2 margin
    assert ual.regions.ask('3', 'hold', *grown(((x3 - h, 4.0, 5.0), (x3 + h, 6.0, 7.0)), pad))[0]
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(0.0, 10.0, 6.0, 0.0)))
    be.clock.sleep(1.5)
    assert any(f.state == 'WAITING_REGION' for f in s.feedback)
    assert abs(ual.pos[1]) < 0.1
    ual.regions.free('3', 'hold')
    assert s.wait(20) == 'succeeded'


def test_pad_boxes_do_not_grow_sideways_so_a_uav_takes_off_between_parked_neighbours(uav):
    """The home pads are 2.6-3.3 m apart: a take-off column grown sideways by the pose error would overlap
    the neighbours' parked boxes as long as they stay landed."""
    agent, ual, be = uav
    parked_h = AgentParams().parked_half_size
    for rid, (x, y) in (('1', (-2.0, 1.65)), ('3', (0.0, 3.3))):       # the arena's UAV pads next to UAV 2's
        assert ual.regions.ask(rid, 'parked', (x - parked_h, y - parked_h, 0.0), (x + parked_h, y + parked_h, 2.0))[0]
    assert take_off(be, 7.0) == 'succeeded'
    for label in GROUND_ANCHORED:
        assert pose_error_pad(label, 0.75, 0.5)[:2] == pytest.approx([0.0, 0.0])


def test_two_uavs_taking_off_from_neighbouring_pads_both_get_their_hold(uav):
    """Seed 107 with hold boxes grown sideways around the reported pose: UAV 1 (pad (-2, 1.65), to 4 m) and
    UAV 2 (pad (0, 0), to 7 m, stopped 0.3 m short) each waited for ever for a hold box overlapping the
    other's take-off column. The take-off's hold is over the pad, as the column: granted."""
    agent, ual, be = uav
    h, mz = C.HOLD_HALF_SIZE, C.POSE_ERROR_MARGIN_Z
    assert ual.regions.ask('1', 'take_off', (-2.0 - h, 1.65 - h, -mz), (-2.0 + h, 1.65 + h, 4.0 + h + mz))[0]
    assert take_off(be, 6.7) == 'succeeded'
    lo, hi = ual.regions.regions()[('2', 'hold')]
    assert lo[:2] == pytest.approx([-h, -h]) and hi[:2] == pytest.approx([h, h])


def test_negative_margins_never_shrink_a_box():
    assert pose_error_pad('hold', -1.0, -2.0) == pytest.approx([0.0, 0.0, 0.0])
