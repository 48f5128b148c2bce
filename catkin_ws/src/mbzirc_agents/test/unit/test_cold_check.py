"""ColdConfirmation: when a water task may stop pumping."""
from mbzirc_agents import constants as C
from mbzirc_agents.tasks.cold_check import NO_FLOW_TIME, ColdConfirmation, WaterFlow, dry_tank_verdict


def test_cold_needs_hot_first_then_consecutive_colds():
    c = ColdConfirmation(checks=3)
    assert not any(c.update(False) for _ in range(10))      # never seen hot: not "out"
    assert not c.update(True)
    assert not c.update(False) and not c.update(False)
    assert c.update(False) and c.out


def test_a_hot_answer_restarts_the_count_and_silence_keeps_it():
    c = ColdConfirmation(checks=3)
    c.update(True)
    c.update(False)
    c.update(False)
    c.update(True)                      # a flicker of heat: the fire still needs water
    assert not c.update(False) and not c.update(False)
    assert not c.update(None)           # detector silent: no evidence, no change
    assert c.update(False)


def test_cold_answers_count_only_with_water_flowing_at_the_fire():
    """Seen hot, then cold while no water flowed at it (the robot looked away, the pump moved no water): those
    answers say nothing and end the row; only a full row of watered cold answers is "out"."""
    c = ColdConfirmation(checks=3)
    c.update(True)
    assert not any(c.update(False, watered=False) for _ in range(10))
    assert not c.update(False) and not c.update(False)
    assert not c.update(False, watered=False)          # the row starts again
    assert not c.update(False) and not c.update(False)
    assert c.update(False)


def test_water_flows_while_the_tank_level_drops():
    f = WaterFlow(now=0.0, window=1.5)
    assert not f.update(2.0, 0.5)                       # a first reading: nothing to compare with
    assert f.update(1.9, 1.0)                           # dropped
    assert f.update(1.9, 2.0)                           # the level comes at a few Hz: dropped 1 s ago
    assert not f.update(1.9, 2.6)                       # still for longer than the window
    assert f.dry_for(2.6) == 1.6
    assert not f.update(float('nan'), 3.0)              # no reading: no evidence
    assert WaterFlow(now=0.0).dry_for(4.0) == 4.0       # never flowed: dry since watching began


def test_a_pump_that_moves_no_water_stalls_the_task_with_why():
    f = WaterFlow(now=0.0)
    assert f.stalled(NO_FLOW_TIME, 3) is None
    why = f.stalled(NO_FLOW_TIME + 0.5, 3)
    assert 'no water flows' in why and 'unknown (no reading)' in why and 'fire 3' in why
    f.update(1.5, 1.0)
    f.update(1.4, 2.0)                                  # flowed at 2 s: not stalled until 2 s + NO_FLOW_TIME
    assert f.stalled(2.0 + NO_FLOW_TIME, 3) is None
    assert '1.40 L' in f.stalled(2.5 + NO_FLOW_TIME, 3)


def test_default_checks_is_the_constant():
    assert ColdConfirmation().checks == C.COLD_CHECKS


def test_dry_tank_verdict_is_sensing_only():
    """A dry tank says nothing about the fire: out only when it read cold `checks` times in a row while the
    water still flowed; cold answers after the last drop, or fewer of them, leave it for a top-up (however
    many litres were pumped: how much a fire needs is unknown)."""
    c = ColdConfirmation(checks=3)
    c.update(True)
    c.update(False)
    c.update(False)
    out, why = dry_tank_verdict(c)
    assert not out and 'top-up' in why and '2 so far' in why
    c.update(False)
    assert dry_tank_verdict(c) == (True, 'cold with water flowing')
    never_hot = ColdConfirmation(checks=3)
    for _ in range(5):
        never_hot.update(False)
    assert not dry_tank_verdict(never_hot)[0]
