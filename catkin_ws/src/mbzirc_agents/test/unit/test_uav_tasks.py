"""UAV tasks against a fake kinematic UAL (no ROS): take-off, regions, preemption, bad goals."""

import numpy as np
import pytest
import rospy
from mbzirc_comm_objs.msg import GoToGoal, Object, ObjectList, TakeOffGoal, ExtinguishFacadeFireGoal, LandGoal

from fake_backend import FakeBackend
from fake_ual import goal_pose, start_uav, stop_agent
from mbzirc_agents import constants as C


@pytest.fixture
def uav():
    be = FakeBackend()
    agent, ual = start_uav(be, speedup=8.0)
    yield agent, ual, be
    stop_agent(agent, ual, be)


def take_off(be, h=3.0):
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=h))
    return s.wait(10)


def test_task_set_and_servers(uav):
    agent, _, be = uav
    assert set(be.servers) == {f'{n}_action' for n in (
        'take_off', 'land', 'go_to', 'follow_path', 'hover', 'search_facade', 'go_to_facade_fire',
        'extinguish_facade_fire', 'look_for_ground_fires', 'extinguish_ground_fire', 'enter_building',
        'search_indoor', 'extinguish_indoor_fire', 'go_home_and_refill')}


def test_take_off_reserves_column_then_holds(uav):
    agent, ual, be = uav
    assert take_off(be) == 'succeeded'
    assert ual.state == 4 and ual.pos[2] == pytest.approx(3.0, abs=0.3)
    regions = ual.regions.regions()
    assert ('2', 'hold') in regions and ('2', 'take_off') not in regions and ('2', 'parked') not in regions


def test_take_off_bad_height(uav):
    _, _, be = uav
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=float('nan')))
    assert s.wait() == 'aborted' and 'height' in s.result.message


def test_go_to_waits_for_region_of_another_agent(uav):
    agent, ual, be = uav
    assert take_off(be) == 'succeeded'
    assert ual.regions.ask('3', 'hold', (4, -1, 2), (6, 1, 4))[0]      # another UAV on the way
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(10, 0, 3)))
    be.clock.sleep(1.0)
    assert any(f.state == 'WAITING_REGION' for f in s.feedback)
    assert np.linalg.norm(ual.pos[:2]) < 0.1                            # did not move
    ual.regions.free('3', 'hold')
    assert s.wait(10) == 'succeeded'
    assert ual.pos == pytest.approx([10, 0, 3], abs=0.35)
    assert ('2', 'go_to') not in ual.regions.regions()


def test_go_to_around_the_building_never_crosses_it(uav):
    agent, ual, be = uav
    assert take_off(be, 3.0) == 'succeeded'
    ual.waypoints.clear()
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(30, 24, 3)))     # beyond the tower's far corner
    assert s.wait(20) == 'succeeded'
    from mbzirc_arena.routing import segment_hits_rect as _segment_hits_rect
    pts = [np.zeros(2)] + [w[0][:2] for w in ual.waypoints]
    assert len(pts) > 2
    for a, b in zip(pts[:-1], pts[1:]):
        for bld in C.BUILDINGS:
            assert not _segment_hits_rect(a, b, bld[:4])


@pytest.mark.parametrize('goal,words', [(goal_pose(float('nan'), 0, 3), 'NaN'), (goal_pose(500, 0, 3), 'outside'),
                                        (goal_pose(1, 1, 3, frame='map'), 'frame')])
def test_go_to_bad_goals(uav, goal, words):
    _, _, be = uav
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal))
    assert s.wait() == 'aborted' and words in s.result.message


def preempt_a_go_to(be):
    """Take off, fly a go-to towards a far point for 1 s, preempt it."""
    assert take_off(be) == 'succeeded'
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(-15, 30, 3)))
    be.clock.sleep(1.0)
    s.preempt = True
    assert s.wait(5) == 'preempted'


def test_preempted_go_to_stops_the_uav(uav):
    agent, ual, be = uav
    preempt_a_go_to(be)
    be.clock.sleep(0.2)
    p1 = ual.pos.copy()
    be.clock.sleep(0.5)
    assert np.linalg.norm(ual.pos - p1) < 0.05
    assert np.linalg.norm(ual.pos[:2]) > 1.0 and np.linalg.norm(ual.pos[:2] - [-15, 30]) > 5


def test_a_go_to_that_fails_in_the_air_leaves_only_a_hover_box(uav):
    """Realistic seed 110 (benchmark on 19ac3a6): the blanket UAV's go_home ended 'not there after 53 s'
    1.3 m short of its pad and the UAV kept its go_to box (the whole way home) while it hovered idle for
    900 s: both other UAVs' take-offs were refused to the end, and it declined the manager's requests to step
    aside ('our boxes in the way: go_to'). Rule: a flying UAV whose task fails or is preempted keeps a hover
    box where it is and frees the way it was flying."""
    agent, ual, be = uav
    preempt_a_go_to(be)
    be.clock.sleep(0.3)
    mine = {label for aid, label in ual.regions.regions() if aid == '2'}
    assert 'go_to' not in mine and 'hold' in mine, mine


def test_a_uav_landed_by_a_preempted_land_holds_only_its_parked_box(uav):
    """Realistic seed 102 (helper C's run on ae45e51): the central unit's heartbeat loss preempted UAV 3's
    landing; the UAL landed it anyway (a landing cannot be held), the task ended with its 'land' column
    reserved and nothing freed it for 230 s (the next go-home found the UAV landed and skipped the landing
    that frees it): UAV 2's go-to was refused all that time. Rule: a landed idle UAV holds only its parked box."""
    agent, ual, be = uav
    assert take_off(be, 20.0) == 'succeeded'
    s = be.servers['land_action']
    s.send(LandGoal())
    for _ in range(100):
        be.clock.sleep(0.02)
        if agent.ual_state == C.UAL_LANDING:
            break
    assert agent.ual_state == C.UAL_LANDING
    s.preempt = True
    assert s.wait(5) == 'preempted'
    for _ in range(200):
        be.clock.sleep(0.1)
        if agent.ual_state in (C.UAL_LANDED_DISARMED, C.UAL_LANDED_ARMED):
            break
    be.clock.sleep(3.0)
    mine = {label for aid, label in ual.regions.regions() if aid == '2'}
    assert mine == {'parked'}, mine


def test_unknown_fire_id_aborted(uav):
    agent, _, be = uav
    s = be.servers['extinguish_facade_fire_action']
    s.send(ExtinguishFacadeFireGoal(fire_id=42))
    assert s.wait() == 'aborted' and 'unknown fire id 42' in s.result.message
    o = Object(id=7, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_GROUND, status=C.STATUS_ACTIVE)
    be.subs['/estimated_objects'](ObjectList(objects=[o]))
    s.send(ExtinguishFacadeFireGoal(fire_id=7))
    assert s.wait() == 'aborted' and 'ground fire' in s.result.message


def test_land_frees_regions(uav):
    agent, ual, be = uav
    assert take_off(be) == 'succeeded'
    s = be.servers['land_action']
    s.send(LandGoal())
    assert s.wait(10) == 'succeeded'
    assert ual.state == 1
    be.clock.sleep(2.5)                      # idle() asks for the parked box at most every 2 s
    # only the parked box (no other UAV may fly low over a landed one) remains
    assert set(ual.regions.regions()) == {('2', 'parked')}
    lo, hi = ual.regions.regions()[('2', 'parked')]
    assert lo[2] == 0.0 and hi[2] >= 2.0 and np.all(lo[:2] <= ual.pos[:2]) and np.all(hi[:2] >= ual.pos[:2])


def test_data_feed_and_cost(uav):
    agent, ual, be = uav
    feed = agent.data_feed()
    assert feed.agent_id == '2' and feed.robot_type == 'uav' and feed.is_idle
    from mbzirc_comm_objs.srv import GetCostToGoToRequest
    assert be.services['get_cost_to_go_to'](GetCostToGoToRequest(waypoint=goal_pose(3, 4, 0))).cost == \
        pytest.approx(5.0, abs=0.01)
    assert be.services['get_cost_to_go_to'](GetCostToGoToRequest(waypoint=goal_pose(float('nan'), 4, 0))).cost == -1


def _beating(agent, period=0.1):
    """A central unit sending heartbeats until the returned event is set."""
    import threading
    stop = threading.Event()

    def loop():
        while not agent.backend.clock.wait(stop, period):
            agent._on_heartbeat(None)
    agent._on_heartbeat(None)
    agent.backend.clock.start_thread(loop, name='central unit heartbeat')
    return stop


def test_heartbeat_loss_aborts_task_and_rejects_goals(uav):
    agent, ual, be = uav
    agent.watchdog.timeout = 0.3
    agent.watchdog.return_home_timeout = 100
    beat = _beating(agent)
    assert take_off(be) == 'succeeded'
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(-15, 30, 3)))
    be.clock.sleep(0.2)
    beat.set()                               # the central unit dies; the agent's own watchdog notices
    assert s.wait(5) == 'aborted' and 'heartbeat' in s.result.message
    s.send(GoToGoal(waypoint=goal_pose(0, 0, 3)))
    assert s.wait(5) == 'aborted' and 'heartbeat' in s.result.message
    beat = _beating(agent)
    deadline = be.clock.now() + 2.0        # the agent's 10 Hz wall-clock watchdog sees it
    while not agent.accepting and be.clock.now() < deadline:
        be.clock.sleep(0.05)
    s.send(GoToGoal(waypoint=goal_pose(0, 0, 3)))
    assert s.wait(10) == 'succeeded'
    beat.set()


def test_heartbeat_watchdog_runs_on_wall_clock_when_ros_time_stops(uav):
    """The link is cut: /clock stops with it (ROS time frozen), yet the loss must be detected."""
    agent, ual, be = uav
    frozen = be.now()
    be.now = lambda: frozen                  # the robot's ROS time no longer advances
    agent.watchdog.timeout = 0.3
    agent.watchdog.return_home_timeout = 0.5
    homes = []
    agent.return_home = lambda: homes.append(be.clock.now()) or None
    agent._on_heartbeat(None)
    assert agent.accepting
    deadline = be.clock.now() + 3.0        # no manual timer calls: the agent's own wall-clock watchdog
    while agent.accepting and be.clock.now() < deadline:
        be.clock.sleep(0.05)
    assert not agent.accepting and 'heartbeat' in agent.reject_reason
    deadline = be.clock.now() + 3.0        # the return_home_timeout countdown runs on wall time too
    while not homes and be.clock.now() < deadline:
        be.clock.sleep(0.05)
    assert homes
    agent._on_heartbeat(None)
    deadline = be.clock.now() + 2.0
    while not agent.accepting and be.clock.now() < deadline:
        be.clock.sleep(0.05)
    assert agent.accepting


def test_gnss_jump_is_doubted_and_the_uav_holds(uav):
    """Bad input: the reported pose jumps 5 m (a GNSS re-fix). The agent logs it (throttled), keeps its last
    pose, holds with zero velocity instead of flying on (no waypoint reaches the UAL meanwhile), and takes
    the new position once it has been reported for ~pose_jump_hold s; a NaN pose is ignored with an error."""
    agent, ual, be = uav
    assert take_off(be) == 'succeeded'
    before = agent.position()[:3].copy()
    n_wp = len(ual.waypoints)
    ual.gnss_offset = np.array([5.0, 0.0, 0.0])
    be.clock.sleep(0.5)
    assert np.allclose(agent.position()[:3], before, atol=0.3) and agent.pose_in_doubt()
    assert any('jumped 5.0 m' in e for e in be.errors)
    agent.send_waypoint(10.0, 10.0, 3.0, 0.0)               # a task's command while in doubt: a hold
    assert len(ual.waypoints) == n_wp
    holds = [m for m in be.pubs.get('ual/set_velocity', []) if m.twist.linear.x == m.twist.linear.y == 0.0]
    assert holds
    be.clock.sleep(3.0 * agent.p.pose_jump_hold)
    assert not agent.pose_in_doubt()
    assert agent.position()[0] == pytest.approx(before[0] + 5.0, abs=0.3)
    nan = goal_pose(float('nan'), 0.0, 3.0, 0.0)
    agent._on_pose(nan)
    assert agent.position()[0] == pytest.approx(before[0] + 5.0, abs=0.3)
    assert any('NaN' in e for e in be.errors)


def test_a_go_to_flies_on_once_a_doubted_gnss_jump_ends(uav):
    """A GNSS jump while a go-to is flown turns it into a hold; once the pose is back (trusted) the leg goes on
    to its end. Before, the set-point was dropped for good and the UAV hovered until the leg timed out
    (ground_station live_page rostest: an operator's recall home failed mid-way)."""
    agent, ual, be = uav
    ual.follow_velocity = True                       # the hold's zero velocity stops the go-to, as in ual_sim
    assert take_off(be) == 'succeeded'
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(12, 0, 3, 0.0)))
    be.clock.sleep(0.5)
    ual.gnss_offset = np.array([5.0, 0.0, 0.0])
    be.clock.sleep(0.3 * agent.p.pose_jump_hold)
    assert agent.pose_in_doubt()
    ual.gnss_offset = np.zeros(3)
    assert s.wait(60) == 'succeeded', s.result.message
    assert ual.pos[0] == pytest.approx(12.0, abs=0.5)


def test_poses_published_seconds_apart_are_no_jump_however_late_they_arrive(uav):
    """A loaded machine: the agent's clock lags, two poses it receives 0.3 s apart by that clock were
    published 3 s apart (their stamps) by a UAV flying at its speed: 4.5 m is flight, not a GNSS jump. The
    same 4.5 m between poses published 0.3 s apart is a jump."""
    agent, ual, be = uav
    assert take_off(be) == 'succeeded'
    on_pose = be.subs['ual/pose']
    be.subs['ual/pose'] = lambda _msg: None          # the fake UAL's own poses no longer reach the agent
    be.clock.sleep(0.2)
    t = be.now()
    start = goal_pose(0.0, 0.0, 3.0, 0.0)
    start.header.stamp = rospy.Time.from_sec(t)
    agent.pose_doubt_since = None
    on_pose(start)
    late = goal_pose(4.5, 0.0, 3.0, 0.0)
    late.header.stamp = rospy.Time.from_sec(t + 3.0)
    on_pose(late)
    assert not agent.pose_in_doubt() and agent.position()[0] == pytest.approx(4.5)
    quick = goal_pose(9.0, 0.0, 3.0, 0.0)
    quick.header.stamp = rospy.Time.from_sec(t + 3.3)
    on_pose(quick)
    assert agent.pose_in_doubt() and agent.position()[0] == pytest.approx(4.5)
    be.subs['ual/pose'] = on_pose


def test_exception_in_the_idle_state_restarts_the_state_machine(uav):
    """A zombie agent: an exception in the idle state ended the state machine's thread while data_feed still
    said idle, and every later goal waited forever. Now the state machine is restarted and goals are served."""
    agent, ual, be = uav
    agent.inject_fault()                                  # the idle state's next step raises
    deadline = be.clock.now() + 2.0
    while agent._inject and be.clock.now() < deadline:
        be.clock.sleep(0.05)
    assert not agent._inject, 'the idle state never ran its next step'
    be.clock.sleep(0.3)
    assert agent._sm_thread.is_alive() and not agent.failed
    assert take_off(be) == 'succeeded'                    # served, not waiting forever


def test_exception_in_a_task_ends_that_task_not_the_agent(uav):
    agent, ual, be = uav
    assert take_off(be) == 'succeeded'
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(-15, 30, 3)))
    be.clock.sleep(0.2)
    agent.inject_fault()
    assert s.wait(5) == 'aborted' and 'fault injected' in s.result.message
    s.send(GoToGoal(waypoint=goal_pose(0, 0, 3)))
    assert s.wait(20) == 'succeeded'


def test_state_machine_that_keeps_dying_marks_the_agent_failed(uav):
    agent, ual, be = uav
    for _ in range(C.SM_MAX_RESTARTS + 1):
        agent.inject_fault()
        deadline = be.clock.now() + 2.0
        while agent._inject and be.clock.now() < deadline:
            be.clock.sleep(0.05)
        be.clock.sleep(0.2)
    deadline = be.clock.now() + 2.0
    while not agent.failed and be.clock.now() < deadline:
        be.clock.sleep(0.05)
    assert agent.failed and not agent._sm_thread.is_alive()
    feed = agent.data_feed()
    assert feed.active_sub_state.startswith('FAILED') and not feed.is_idle   # not a silent "idle"
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=3.0))
    assert s.wait(5) == 'aborted' and 'agent failed' in s.result.message


def _respawned_uav(be, z):
    """A UavAgent '2' started over a FakeUal whose UAV is at height z, with robot 2 holding a region."""
    from fake_ual import FakeUal, start_agent
    from mbzirc_agents.uav_agent import UavAgent
    ual = FakeUal(be, pos=(7.0, 8.0, z), speedup=8.0)
    ual.regions.ask('2', 'go_to', (5, 5, 0), (10, 10, 8))           # held by the previous run
    agent = start_agent(UavAgent('2', be, {'region_timeout': 5.0}), be)
    be.clock.sleep(0.5)
    return agent, ual


def test_respawned_in_the_air_keeps_its_regions_and_takes_the_arena_home():
    from mbzirc_arena.c3 import ARENA
    be = FakeBackend()
    agent, ual = _respawned_uav(be, 6.0)
    try:
        assert ual.regions.owner_at((7, 8, 6)) == '2', 'a respawned UAV freed the airspace it is in'
        arena_home = next(h.position for h in ARENA.homes if h.robot_id == 2)
        assert np.allclose(agent.home, arena_home), 'a first pose mid-air is not home'
    finally:
        stop_agent(agent, ual, be)


def test_started_on_the_ground_frees_a_previous_runs_regions_and_is_home():
    be = FakeBackend()
    agent, ual = _respawned_uav(be, 0.0)
    try:
        assert ual.regions.owner_at((7, 8, 6)) is None
        assert np.allclose(agent.home, (7.0, 8.0, 0.0))
    finally:
        stop_agent(agent, ual, be)


def test_replayed_heartbeats_are_not_believed(uav):
    """A heartbeat replayed from a bag (another mission, or this central unit's old ones) must not keep the
    agent believing a dead central unit is alive."""
    from std_msgs.msg import Header
    agent, ual, be = uav
    agent.set_mission('m1')
    agent.watchdog.timeout = 0.3
    agent.watchdog.return_home_timeout = 100
    agent._on_heartbeat(Header(seq=5, frame_id='central_unit/m1/live'))
    assert agent.accepting
    deadline = be.clock.now() + 3.0
    while agent.accepting and be.clock.now() < deadline:    # the central unit dies; a bag replays beats
        agent._on_heartbeat(Header(seq=99, frame_id='central_unit/m0/old'))    # another mission
        agent._on_heartbeat(Header(seq=3, frame_id='central_unit/m1/live'))    # its own, replayed
        be.clock.sleep(0.05)
    assert not agent.accepting and 'heartbeat' in agent.reject_reason
    agent._on_heartbeat(Header(seq=1, frame_id='central_unit/m1/restarted'))  # a real restart: believed
    deadline = be.clock.now() + 2.0
    while not agent.accepting and be.clock.now() < deadline:
        be.clock.sleep(0.05)
    assert agent.accepting


def test_data_feed_withheld_while_the_state_machine_is_stuck(uav):
    agent, ual, be = uav
    sent = []
    agent.feed_pub = type('P', (), {'publish': lambda self, m: sent.append(m)})()
    agent._last_feed = (None, -1e9)
    agent._on_timer()
    assert sent, 'a working agent sends its data_feed'
    agent.note_sm_alive = lambda: None                              # the state machine stopped working
    agent.sm_beat = be.wall_time() - C.SM_STALL_S - 1
    sent.clear()
    agent._last_feed = (None, -1e9)
    agent._on_timer()
    assert not sent


def test_go_to_a_point_inside_the_building_from_outside_is_refused(uav):
    """A planned go-to (follow_path's legs) to a point inside a building outline, the UAV outside, would fly
    straight into the wall (seen under realistic uncertainty: a waypoint inside the extension, from an
    estimate off by the GNSS error): refused with a clear message, the UAV stays outside."""
    agent, ual, be = uav
    assert take_off(be) == 'succeeded'
    s = be.servers['go_to_action']
    s.send(GoToGoal(waypoint=goal_pose(26.5, 18.8, 1.0)))
    assert s.wait(10) == 'aborted' and 'inside the building outline' in s.result.message
    assert ual.pos[0] < 11.0


def test_landed_uav_boxes_stay_on_its_pad_while_the_gnss_bias_wanders(uav):
    """Realistic seed 102: a refilled UAV waited minutes for its take-off column, refused by the parked box
    of its landed neighbour; both boxes had followed their robots' wandering GNSS bias off the pads."""
    agent, ual, be = uav
    ual.gnss_bias = np.array([0.3, 1.3, 0.0])               # the reported pose of the landed UAV wanders
    be.clock.sleep(2.5)                                      # idle() asks for the parked box every 2 s
    lo, hi = ual.regions.regions()[('2', 'parked')]
    assert np.allclose((lo[:2] + hi[:2]) / 2, agent.home[:2])  # on the pad (robot 2's home), not the fix
    # a neighbour's box that the column over the reported position would overlap, not the pad's
    ok, _ = ual.regions.ask('3', 'parked', (-1.0, 1.2, 0.0), (1.0, 4.0, 2.0))
    assert ok
    assert take_off(be) == 'succeeded'
