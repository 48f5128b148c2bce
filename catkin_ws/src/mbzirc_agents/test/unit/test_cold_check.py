"""ColdConfirmation: when a water task may stop pumping."""
import pytest

from mbzirc_agents import constants as C
from mbzirc_agents.tasks.cold_check import ColdConfirmation, WaterMeter, dry_tank_verdict


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


def test_water_meter_counts_drops_while_pumping_only():
    m = WaterMeter()
    m.update(2.0, False)
    m.update(1.5, True)
    m.update(1.2, False)           # pump off (e.g. off target): not delivered at the fire
    m.update(float('nan'), True)   # no reading: ignored
    m.update(1.0, True)
    m.update(1.4, True)            # a refill reading: never negative
    assert m.litres == pytest.approx(0.7)
    assert m.covers(0.7) and not m.covers(1.0)


def test_water_meter_weights_drops_by_the_aim():
    """Water pumped while the aim is off the hole mostly splashes on the wall: it is credited by its share."""
    m = WaterMeter()
    m.update(2.0, True)
    m.update(1.0, True, 1.0)
    m.update(0.6, True, 0.5)
    m.update(0.2, True, 0.0)
    m.update(0.0, True, 7.0)       # a share is clipped to 0-1
    assert m.litres == pytest.approx(1.0 + 0.2 + 0.0 + 0.2)


def test_dry_tank_verdict():
    """Cold once the last water settled is "out" only after a whole fire's water from this run."""
    def run(litres, answers):
        c = ColdConfirmation(checks=2)
        c.update(True)
        m = WaterMeter()
        m.update(litres, True)
        m.update(0.0, True)
        it = iter(answers)
        return dry_tank_verdict(c, m, 1.0, lambda: next(it, False), lambda s: None)
    assert run(1.5, [False, False]) == (True, 'cold after 1.50 L in')
    out, why = run(0.9, [False, False])
    assert not out and 'top-up' in why and '0.90 L' in why
    assert run(1.5, [True] * 10) == (False, 'still hot, tank empty')
