"""ColdConfirmation: when a water task may stop pumping."""
from mbzirc_agents import constants as C
from mbzirc_agents.tasks.cold_check import NO_FLOW_TIME, ColdConfirmation, Soak, WaterFlow, dry_tank_verdict


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


def test_the_first_cold_answer_starts_a_soak_and_a_hot_one_ends_it():
    """Cold after 2 L: 0.5 L more (a quarter) and at least 1 s before cold answers count; hot meanwhile: the
    fire still shows, aimed on again, and the next cold answer starts a new soak (on the water by then)."""
    s = Soak(fraction=0.25, min_time=1.0)
    assert s.update(True, True, 1.0, 0.0) is True
    assert s.update(None, True, 1.5, 0.5) is None and not s.soaking
    assert s.update(False, False, 1.8, 0.8) is False and not s.soaking    # no water at it: no soak
    assert s.update(False, True, 2.0, 1.0) is None and s.soaking
    assert s.update(False, True, 2.4, 2.5) is None                      # 0.4 L of 0.5: on
    assert s.update(False, True, 2.5, 2.6) is False and not s.soaking   # soaked: cold counts
    assert s.update(False, True, 2.6, 2.7) is False
    assert s.update(True, True, 2.7, 2.8) is True and not s.soaking
    assert s.update(False, True, 3.0, 3.0) is None and s.soaking        # a new soak: 3.75 L, 4 s
    assert s.update(False, True, 3.8, 3.5) is None
    assert s.update(False, True, 3.8, 4.0) is False


def test_a_soak_hides_cold_answers_from_the_cold_check():
    c, s = ColdConfirmation(checks=2), Soak(fraction=0.5, min_time=0.0)
    c.update(s.update(True, True, 0.0, 0.0))
    assert not c.update(s.update(False, True, 1.0, 1.0))               # 1.5 L ends it
    assert not c.update(s.update(False, True, 1.4, 2.0))
    assert not c.update(s.update(False, True, 1.5, 3.0))
    assert c.update(s.update(False, True, 1.6, 4.0))
