"""A deadlock between two UAVs' regions and the step aside that breaks it (fake UAL, simulated clock).

Realistic seed 104: right after take-off UAV 2 (hovering at z 6) and UAV 3 (at z 7.4, 3.3 m north) each
waited the whole trial for a go_to box that overlapped the other's hold box.
"""
import numpy as np
import pytest
from mbzirc_comm_objs.msg import GoToGoal, HoverGoal, TakeOffGoal
from mbzirc_comm_objs.srv import AskForRegionRequest

from fake_backend import FakeBackend
from fake_ual import FakeUal, goal_pose, start_agent, stop_agent
from mbzirc_arena.boxes import boxes_overlap
from mbzirc_agents import constants as C
from mbzirc_agents.region_yield import step_aside_targets
from shared_regions_manager.core import RegionManager

UAV3_HOLD = ((-1.0, 2.3, 6.4), (1.0, 4.3, 8.4))
UAV3_GO_TO = ((-1.0, -5.0, 6.4), (1.0, 4.3, 8.4))         # southwards across UAV 2's hold


def uav_2_and_a_scripted_uav(other):
    """UAV 2 (the agent under test) at its pad; the manager's table shared with a scripted UAV `other`. UAV 2
    has the lower priority, so that it is the one named to step aside."""
    be = FakeBackend()
    rm = RegionManager(known_agents=[other, '2'], priority=[other, '2'], clock=be.clock.now)
    ual = FakeUal(be, speedup=8.0, regions=rm)
    from mbzirc_agents.uav_agent import UavAgent
    agent = start_agent(UavAgent('2', be, {'region_timeout': 60.0}), be)
    yield agent, ual, be, rm
    stop_agent(agent, ual, be)


@pytest.fixture
def two_uavs():
    """UAV 2 and a scripted UAV 3."""
    yield from uav_2_and_a_scripted_uav('3')


def manager_step(be, rm):
    """What the region manager node does at its timer: find a deadlock, ask the victim, report its answer."""
    order = rm.deadlock()
    if order is None:
        return None
    req = AskForRegionRequest(agent_id=order.winner, label=order.winner_label)
    (req.min_corner.point.x, req.min_corner.point.y, req.min_corner.point.z) = order.box[0]
    (req.max_corner.point.x, req.max_corner.point.y, req.max_corner.point.z) = order.box[1]
    accepted = be.services['yield_region'](req).success
    rm.yield_answer(order, accepted)
    return order, accepted


def wait_for_region(be, rm, agent_id, box, seconds=60.0):
    """The scripted robot asks for its go_to box at 2 Hz while the manager runs at 2 Hz: (ROS time it was
    granted or None, the manager's (order, accepted) meanwhile)."""
    orders = []
    for _ in range(int(seconds * 2)):
        if rm.ask(agent_id, 'go_to', *box)[0]:
            return be.clock.now(), orders
        got = manager_step(be, rm)
        if got:
            orders.append(got)
        be.clock.sleep(0.5)
    return None, orders


def test_two_uavs_each_waiting_for_the_others_hold_box_no_longer_wait_forever(two_uavs):
    agent, ual, be, rm = two_uavs
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=6.0))
    assert s.wait(20) == 'succeeded'
    assert rm.ask('3', 'hold', *UAV3_HOLD)[0]
    go = be.servers['go_to_action']
    go.send(GoToGoal(waypoint=goal_pose(0.0, 8.0, 6.0, 0.0)))          # northwards across UAV 3's hold
    granted_at, orders = wait_for_region(be, rm, '3', UAV3_GO_TO)
    assert granted_at is not None, f'UAV 3 waited for ever (orders: {orders})'
    assert [(o.victim, o.winner, ok) for o, ok in orders] == [('2', '3', True)]
    # UAV 2 left UAV 3's box for a place of its own, by the shortest step (down, out of the box's floor)
    regions = rm.regions()
    assert not boxes_overlap(regions[('2', 'hold')], regions[('3', 'go_to')])
    assert ('2', 'step_aside') not in regions
    assert ual.pos[2] < 5.2 and np.hypot(ual.pos[0], ual.pos[1]) < 0.3
    # UAV 3 flies through and away: UAV 2's go-to then goes on from where it stepped to
    rm.free('3', free_all=True)
    assert go.wait(40) == 'succeeded'
    assert ual.pos == pytest.approx([0.0, 8.0, 6.0], abs=0.35)


def test_every_step_taken_by_others_the_uav_stays_and_waits_on(two_uavs):
    """Robot 1 holds the boxes of all four steps: UAV 2 accepted, finds no step granted, does not move and
    holds no step box; its go-to still waits (the manager asks again after ~yield_retry)."""
    agent, ual, be, rm = two_uavs
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=6.0))
    assert s.wait(20) == 'succeeded'
    assert rm.ask('3', 'hold', *UAV3_HOLD)[0]
    # (clear of UAV 2's hold box as the manager holds it: grown by the pose error, pose_error_boxes.py)
    for i, box in enumerate((((-1, -1, 3.0), (1, 1, 4.5)), ((-4.5, -1, 5), (-1.8, 1, 7)),
                             ((1.8, -1, 5), (4.5, 1, 7)), ((-1, -1, 8.5), (1, 1, 10)))):
        assert rm.ask('1', f'x{i}', *box)[0]
    go = be.servers['go_to_action']
    go.send(GoToGoal(waypoint=goal_pose(0.0, 8.0, 6.0, 0.0)))
    orders = []
    for _ in range(20):
        assert not rm.ask('3', 'go_to', *UAV3_GO_TO)[0]
        got = manager_step(be, rm)
        if got:
            orders.append(got)
        be.clock.sleep(0.5)
    assert [(o.victim, ok) for o, ok in orders] == [('2', True)]
    assert ual.pos == pytest.approx([0.0, 0.0, 6.0], abs=0.2)
    assert ('2', 'step_aside') not in rm.regions() and not go.done.is_set()
    assert any('cannot step out of 3/go_to' in w for w in be.warns)


def test_a_uav_busy_but_not_waiting_for_a_region_declines_to_step_aside(two_uavs):
    agent, ual, be, rm = two_uavs
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=6.0))
    assert s.wait(20) == 'succeeded'
    hover = be.servers['hover_action']
    hover.send(HoverGoal(duration=0.0))                        # working where it is (a task, no region wait)
    be.clock.sleep(1.0)
    req = AskForRegionRequest(agent_id='3', label='go_to')
    (req.min_corner.point.x, req.min_corner.point.y, req.min_corner.point.z) = UAV3_GO_TO[0]
    (req.max_corner.point.x, req.max_corner.point.y, req.max_corner.point.z) = UAV3_GO_TO[1]
    assert not be.services['yield_region'](req).success       # it frees its boxes when its work ends
    req.min_corner.point.x = float('nan')
    assert not be.services['yield_region'](req).success


def test_an_idle_hovering_uav_steps_out_of_the_box_a_robot_waits_long_for(two_uavs):
    """No cycle: UAV 2 hovers with no work over UAV 3's way, UAV 3 waits. The manager's idle-holder rule
    asks UAV 2 after ~idle_yield_after; the idle UAV steps aside by itself and UAV 3's box is granted."""
    agent, ual, be, rm = two_uavs
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=6.0))
    assert s.wait(20) == 'succeeded'
    assert rm.ask('3', 'hold', *UAV3_HOLD)[0]
    granted_at, orders = wait_for_region(be, rm, '3', UAV3_GO_TO)
    assert granted_at is not None, f'UAV 3 waited for ever (orders: {orders}, warnings: {be.warns[-3:]})'
    assert [(o.victim, o.winner, ok) for o, ok in orders] == [('2', '3', True)]
    assert orders[0][0].idle_for >= 15.0
    regions = rm.regions()
    assert not boxes_overlap(regions[('2', 'hold')], regions[('3', 'go_to')]) and ('2', 'step_aside') not in regions
    assert ual.pos[2] < 5.2 and np.hypot(ual.pos[0], ual.pos[1]) < 0.3


def test_step_targets_shortest_first_inside_the_arena_and_never_near_a_wall():
    box = (np.array([-1.0, -5.0, 6.4]), np.array([1.0, 4.3, 8.4]))
    targets = step_aside_targets((0.0, 0.0, 6.0), 1.0, box, C.ARENA_BOX, C.BUILDINGS, 1.5, 2.0, 4.0)
    assert [tuple(np.round(t, 2)) for t in targets] == [(0.0, 0.0, 5.1), (-2.3, 0.0, 6.0), (2.3, 0.0, 6.0),
                                                        (0.0, 0.0, 9.7)]
    # beside the tower's west wall (x 11.4), 2 m off: a step east would be into the wall, none is offered there
    near = (9.4, 12.0, 6.0)
    box = (np.array([8.0, 5.0, 5.5]), np.array([10.5, 20.0, 6.5]))
    targets = step_aside_targets(near, 1.0, box, C.ARENA_BOX, C.BUILDINGS, 1.5, 2.0, 4.0)
    assert targets and all(t[0] <= near[0] + 1e-9 for t in targets)
    # never below min_z, never longer than max_step
    low = step_aside_targets((0.0, 0.0, 2.5), 1.0, (np.array([-1.0, -1.0, 2.0]), np.array([1.0, 1.0, 9.0])),
                             C.ARENA_BOX, C.BUILDINGS, 1.5, 2.0, 2.5)
    assert [tuple(np.round(t, 2)) for t in low] == [(-2.3, 0.0, 2.5), (2.3, 0.0, 2.5), (0.0, -2.3, 2.5),
                                                    (0.0, 2.3, 2.5)]


# Realistic seed 108 (t 15-378 s): UAV 1 hovered over its pad (-2, 1.65) at its transit altitude (reported
# z 4.5) and UAV 2 over its pad (0, 0) at z 7.3; their hold boxes, placed over the pads and grown in z only
# (pose_error_boxes.py), touched at x -1 and overlapped in z by 0.2 m. Each one's go_to overlapped the
# other's hold: a deadlock. UAV 2 (lower priority) accepted every order, but its step box, swept around its
# reported pose and grown 0.75 m sideways, overlapped UAV 1's hold where its own hold did not: 'no step
# granted', twenty times, and the blanket UAV never flew.
UAV1_HOLD_108 = ((-3.0, 0.65, 3.0), (-1.0, 2.65, 6.0))
UAV1_GO_TO_108 = ((-11.5, 0.6, 2.5), (-0.3, 9.6, 5.9))


@pytest.fixture
def seed_108():
    """UAV 2 and a scripted UAV 1."""
    yield from uav_2_and_a_scripted_uav('1')


def test_seed_108_uav_over_its_pad_steps_out_of_the_neighbours_box_by_its_held_hold_box(seed_108):
    agent, ual, be, rm = seed_108
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=7.3))
    assert s.wait(20) == 'succeeded'
    assert rm.ask('1', 'hold', *UAV1_HOLD_108)[0]              # side by side: the holds only touch
    go = be.servers['go_to_action']
    go.send(GoToGoal(waypoint=goal_pose(30.0, 0.0, 7.5, 0.0)))  # eastwards: its box overlaps UAV 1's hold
    granted_at, orders = wait_for_region(be, rm, '1', UAV1_GO_TO_108)
    assert granted_at is not None, f'UAV 1 waited for ever (orders: {[(o.victim, ok) for o, ok in orders]}, ' \
                                   f'warnings: {be.warns[-3:]})'
    regions = rm.regions()
    assert not boxes_overlap(regions[('2', 'hold')], regions[('1', 'go_to')])
    assert ('2', 'step_aside') not in regions
    # straight up over its pad, by the shortest step (0.4 m + the clearance)
    assert np.hypot(ual.pos[0], ual.pos[1]) < 0.3 and 7.5 < ual.pos[2] < 8.2
