"""extinguish_indoor_fire in closed loop with ual_sim's realistic world (sim_ual.py): the real task, the real
fire detector, the simulator's renderer, GNSS bias, gusts and jet; the simulator only referees.

Why: the scripted cameras of test_indoor_water.py test the rules one at a time; whether one tank puts out a
fire needing 0.8-1.3 L, and whether "out" is said only of a fire that is out, only the simulator's truth tells.
Seeds and holders here were not used to tune the task (bench/bench_indoor_pour.py runs the larger matrix)."""
import pytest

from sim_ual import pour

POURS = [(seed, holder) for seed in (31, 32, 33, 34) for holder in ('in0_w', 'in1_e', 'in2_w')]


@pytest.fixture(scope='module')
def outcomes():
    return [pour(seed, holder=holder) for seed, holder in POURS]


def test_a_fire_is_never_judged_out_short_of_the_water_it_needs(outcomes):
    """The verdict comes from the thermal camera (cold with the pump off), never from litres pumped: no pour
    says 'out' of a fire the referee still counts burning (before the raw-image rules: one at 99.9 %)."""
    wrong = [(p, o['progress'], o['message']) for p, o in zip(POURS, outcomes)
             if o['extinguished'] and o['progress'] < 1.0]
    assert not wrong, wrong


def test_one_tank_puts_out_and_confirms_nearly_every_indoor_fire(outcomes):
    """A 2 L tank, fires needing 0.8-1.3 L, GNSS bias and gusts: put out and confirmed by the first tank in
    at least 10 of 12 pours (before the aim was steered every 0.1 s, the lock taken again after a turn and a
    soak cut short by a dry tank confirmed: 26 of 72 over seeds 1-12, 35 left for a top-up trip when out)."""
    good = [p for p, o in zip(POURS, outcomes) if o['extinguished'] and o['progress'] >= 1.0]
    detail = [(p, round(o['progress'], 3), o['message'][:60]) for p, o in zip(POURS, outcomes)]
    assert len(good) >= 10, detail


TOP_UPS = POURS                  # the same untuned seeds and holders, each fire left at 97 % by a dry tank


@pytest.fixture(scope='module')
def top_ups():
    return [pour(seed, holder=holder, progress=0.97) for seed, holder in TOP_UPS]


def test_a_top_up_never_judges_out_a_fire_nearly_out_that_it_did_not_finish(top_ups):
    """A fire left at 97 % stands only a few degC over its wall, under the detector's test, and reads cold
    soon after water: a pour whose jet missed it must not call it out (before the ring of flames was looked
    for under a warmer wall: 2 of these 12 judged out at 97 %, no water in)."""
    wrong = [(p, o['progress'], o['message']) for p, o in zip(TOP_UPS, top_ups)
             if o['extinguished'] and o['progress'] < 1.0]
    assert not wrong, wrong


def test_a_top_up_finds_a_faint_fire_by_its_ring_of_flames(top_ups):
    """The look beside the watering pose takes a ring of flames around a cooler hole however faint (a
    sun-heated wall rings none), not only an area 10 degC over its wall: at least 4 of the 12 fires at 97 %
    finished and confirmed (before: 1; realistic seed 101's in2_e stayed at 97 % through two top-ups)."""
    good = [p for p, o in zip(TOP_UPS, top_ups) if o['extinguished'] and o['progress'] >= 1.0]
    detail = [(p, round(o['progress'], 3), o['message'][:60]) for p, o in zip(TOP_UPS, top_ups)]
    assert len(good) >= 4, detail


@pytest.mark.parametrize('seed', [1, 2, 7])
def test_ideal_7_a_top_up_whose_looks_outlast_the_pose_history_turns_onto_the_fire_it_saw(seed, monkeypatch):
    """A top-up of in1_e at 0.943 (out of the detector's reach): the look straight ahead sees its ring of flames,
    and the looks beside, above and below it take longer than the pose history holds (here 2 s of poses; in
    the mission 200 poses of ual_sim's 30 Hz, against ~10 s of looks). The ring's bearing must be taken with
    the pose of its own frame, not with the oldest pose left in the history (a look's 29 deg aside: ideal
    seed 7 at RTF 4, five tanks 0.6 m beside the fire, left at 0.943): the fire is filled."""
    from mbzirc_agents import constants as C
    monkeypatch.setattr(C, 'POSE_HISTORY_LEN', 40)
    r = pour(seed, holder='in1_e', profile_name='ideal', progress=0.943)
    assert r['progress'] >= 1.0, (r['message'], r['into'])
