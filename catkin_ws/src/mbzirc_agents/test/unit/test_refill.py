"""go_home_and_refill against the fake UAL, with the competition's reset as the test's rule: a full tank
after RESET_TIME s landed within PAD_RADIUS of the robot's home pad (true position). The landing is flown on
GNSS, whose error moves the robot off the pad."""
import contextlib
import threading

import numpy as np
from mbzirc_comm_objs.msg import GoHomeAndRefillGoal, TakeOffGoal
from uav_abstraction_layer.msg import State

from fake_backend import FakeBackend
from fake_ual import start_uav, stop_agent

PAD_RADIUS, RESET_TIME = 1.5, 5.0     # the test's reset rule
HOME = np.zeros(2)                    # robot 2's pad in the arena model


class Reset:
    """The human reset: refills the fake UAL's tank once it has been landed near the pad for RESET_TIME s;
    counts the take-offs it sees."""

    def __init__(self, be, ual):
        self.stop, self.take_offs, self.landings = False, 0, []
        landed_since, was_landed = None, True

        def loop():
            nonlocal landed_since, was_landed
            while not self.stop:
                landed = ual.state == State.LANDED_DISARMED
                if landed and not was_landed:
                    self.landings.append(float(np.linalg.norm(ual.pos[:2] - HOME)))
                if was_landed and not landed:
                    self.take_offs += 1
                was_landed = landed
                near = landed and np.linalg.norm(ual.pos[:2] - HOME) <= PAD_RADIUS
                landed_since = (landed_since or be.clock.now()) if near else None
                if near and be.clock.now() - landed_since >= RESET_TIME:
                    ual.water = 2.0
                be.clock.sleep(0.1)
        be.clock.start_thread(loop, name='reset')


def fly_out(be, ual):
    s = be.servers['take_off_action']
    s.send(TakeOffGoal(height=3.0))
    assert s.wait(20) == 'succeeded', s.result.message
    ual.water = 0.3


@contextlib.contextmanager
def refill_scene(params=None):
    """Robot 2 (params for its agent) with the test's reset rule; stopped at the end whatever happens."""
    be = FakeBackend()
    agent, ual = start_uav(be, params or {}, speedup=4.0)
    reset = Reset(be, ual)
    try:
        yield be, agent, ual, reset
    finally:
        reset.stop = True
        stop_agent(agent, ual, be)


def wander(be, ual, start, end, after_landings, reset, seconds=10.0):
    """The GNSS bias is start (set before the take-off: a step later is a pose jump, which the agent
    doubts) and moves to end over `seconds` once the robot has landed after_landings times."""
    ual.gnss_bias = np.array(start, float)

    def loop():
        while len(reset.landings) < after_landings and not reset.stop:
            be.clock.sleep(0.1)
        t0 = be.clock.now()
        while not reset.stop and be.clock.now() - t0 < seconds:
            k = (be.clock.now() - t0) / seconds
            ual.gnss_bias = (1 - k) * np.array(start, float) + k * np.array(end, float)
            be.clock.sleep(0.1)
        ual.gnss_bias = np.array(end, float)
    be.clock.start_thread(loop, name='gnss')


def test_a_uav_landed_off_its_pad_by_its_gnss_error_lands_on_it_again():
    """Realistic seed 102: the blanket UAV landed 1.3-1.5 m off its pad (GNSS) and waited for the reset
    the whole trial. Here it lands 1.8 m off; the error then moves to 0.3 m: no reset within ~reland_after
    s -> it takes off and lands again, on the pad this time, and is refilled."""
    with refill_scene() as (be, agent, ual, reset):
        wander(be, ual, (1.8, 0.0, 0.0), (0.3, 0.0, 0.0), after_landings=1, reset=reset)
        fly_out(be, ual)
        s = be.servers['go_home_and_refill_action']
        s.send(GoHomeAndRefillGoal())
        assert s.wait(400) == 'succeeded', s.result.message
        assert reset.landings[0] > PAD_RADIUS and reset.landings[-1] <= PAD_RADIUS, reset.landings
        assert len(reset.landings) == 2 and reset.take_offs == 2, (reset.landings, reset.take_offs)
        assert any('landing on it again' in m for m in be.warns), be.warns


def test_landings_again_are_bounded_then_the_task_fails():
    """An error that stays 1.8 m: ~reland_attempts landings again, then the ~refill_timeout wait, then a
    failure the central unit sees (not a wait for ever)."""
    with refill_scene({'reland_attempts': 1, 'refill_timeout': 10.0}) as (be, agent, ual, reset):
        ual.gnss_bias = np.array((1.8, 0.0, 0.0))
        fly_out(be, ual)
        s = be.servers['go_home_and_refill_action']
        s.send(GoHomeAndRefillGoal())
        assert s.wait(400) == 'aborted', s.result.message
        assert 'timeout' in s.result.message and len(reset.landings) == 2, (s.result.message, reset.landings)


def test_a_uav_landed_off_its_pad_after_a_failed_refill_takes_off_to_land_on_it_when_asked_again():
    """Realistic seed 105 (benchmark on 5882eb8): UAV 2 landed three times off its pad by its GNSS error, no
    reset came, go_home_and_refill timed out; its error then shrank, so its GNSS put it (truly) 1.5+ m off
    home, and every later go_home_and_refill was refused at once, 'landed away from home: take off first':
    the central unit counted it broken and it stood there from 490 s to the end (one water UAV of two). Rule:
    going home, a UAV landed away from home takes off and lands on its pad again itself."""
    with refill_scene({'reland_attempts': 1, 'refill_timeout': 10.0}) as (be, agent, ual, reset):
        wander(be, ual, (1.8, 0.0, 0.0), (0.0, 0.0, 0.0), after_landings=2, reset=reset)
        fly_out(be, ual)
        s = be.servers['go_home_and_refill_action']
        s.send(GoHomeAndRefillGoal())
        assert s.wait(400) == 'aborted', s.result.message
        assert np.linalg.norm(agent.position()[:2] - HOME) > 1.5, agent.position()
        s.send(GoHomeAndRefillGoal())
        assert s.wait(400) == 'succeeded', s.result.message
        assert reset.landings[-1] <= PAD_RADIUS, reset.landings


def test_the_landing_is_aimed_off_the_pad_away_from_the_neighbours_pads():
    """Realistic seeds 104-107: UAVs landing on GNSS beside a neighbour's pad (2.6 m away) came down ~1 m
    from it. Robot 2 (pad (0, 0); pads (-2, 1.65) and (0, 3.3) beside it) now aims ~home_landing_offset
    off its pad, away from both: with no GNSS error it lands 0.5 m off its centre, each neighbour's pad at
    least 2.9 m away (2.59 m when landing on the centre), and is refilled all the same."""
    with refill_scene() as (be, agent, ual, reset):
        fly_out(be, ual)
        s = be.servers['go_home_and_refill_action']
        s.send(GoHomeAndRefillGoal())
        assert s.wait(400) == 'succeeded', s.result.message
        assert len(reset.landings) == 1 and abs(reset.landings[0] - 0.5) < 0.15, reset.landings
        for pad in ((-2.0, 1.65), (0.0, 3.3)):
            assert np.linalg.norm(ual.pos[:2] - np.array(pad)) >= 2.9, (ual.pos, pad)


def test_a_uav_with_a_large_gnss_error_lands_on_its_pad_by_its_laser_the_first_time():
    """Realistic seed 105: UAV 2 landed off its pad by its GNSS error three times in a row (its error stayed
    large in one direction for a minute) and was never refilled (idle 716 s). The buildings' outline is known
    and the laser sees facade C and the south faces from the pads: the error is measured there and the UAV
    lands on its pad the first time, even with a 1.8 m error that goes on wandering on the way down."""
    from laser_world import LaserScene
    with refill_scene() as (be, agent, ual, reset):
        scene = LaserScene(be, ual)
        try:
            wander(be, ual, (1.8, -0.9, 0.0), (1.5, -0.5, 0.0), after_landings=0, reset=reset, seconds=60.0)
            fly_out(be, ual)
            s = be.servers['go_home_and_refill_action']
            s.send(GoHomeAndRefillGoal())
            assert s.wait(400) == 'succeeded', s.result.message
            assert len(reset.landings) == 1 and reset.take_offs == 1, (reset.landings, reset.take_offs)
            assert abs(reset.landings[0] - 0.5) < 0.3, reset.landings        # on its landing spot
            assert any('GNSS error by the laser' in m for m in be.infos), be.infos
        finally:
            scene.stop = True


def test_realistic_106_a_correction_low_over_the_pad_that_does_not_arrive_ends_in_a_landing_not_a_hover():
    """Realistic seed 106: the laser's second fix, 1 m over the pad, asked for a 0.7 m move that never arrived;
    the task failed with the UAV hovering there, and its hover box and a neighbour's way home locked each other
    for the rest of the trial (both water UAVs idle from 280 s). Here no go-to below 2 m moves the UAV
    sideways: it lands where it is and the refill goes on (a landing off the pad is tried again)."""
    from laser_world import LaserScene
    with refill_scene() as (be, agent, ual, reset):
        scene = LaserScene(be, ual)
        go_to = be.handlers['ual/go_to_waypoint']

        def stuck_low(req):                          # below 2 m the UAV keeps its x, y (as seed 106's did)
            p = req.waypoint.pose.position
            if p.z < 2.0:
                p.x, p.y = float(ual.pos[0]), float(ual.pos[1])
            return go_to(req)
        be.handlers['ual/go_to_waypoint'] = stuck_low
        task = agent.specs['go_home_and_refill'].task
        fixes = iter([(0.0, 0.0), (0.7, 0.0)])           # high over the pad, then low: the error moved 0.7 m
        task._gnss_error = lambda what: next(fixes, None)
        try:
            fly_out(be, ual)
            s = be.servers['go_home_and_refill_action']
            s.send(GoHomeAndRefillGoal())
            assert s.wait(400) == 'succeeded', s.result.message
            assert reset.landings, 'it never landed'
            assert any('landing where it is' in m for m in be.warns), be.warns
        finally:
            scene.stop = True
