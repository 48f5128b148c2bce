"""ColdConfirmation: when a water task may stop pumping."""
from mbzirc_agents import constants as C
from mbzirc_agents.tasks.cold_check import ColdConfirmation


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


def test_default_checks_is_the_constant():
    assert ColdConfirmation().checks == C.COLD_CHECKS


def test_settle_waits_for_the_last_water_to_show():
    """Tank dry while the detector still filters the last hot frames: cold answers that follow count."""
    c = ColdConfirmation(checks=3)
    c.update(True)
    answers = iter([True, False, False, False, False])
    naps = []
    assert c.settle(lambda: next(answers), naps.append, period=0.5)
    assert naps == [0.5, 0.5, 0.5] and c.out


def test_settle_gives_up_after_checks_answers():
    c = ColdConfirmation(checks=3)
    c.update(True)
    naps = []
    assert not c.settle(lambda: True, naps.append)
    assert len(naps) == 6
