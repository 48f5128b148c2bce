"""The operator's gate of the central unit: start, pause, resume (pure part; the services are thin)."""
from mbzirc_central_unit.operator import OperatorGate


def test_starts_at_once_unless_told_to_wait():
    assert OperatorGate().deciding()
    gate = OperatorGate(wait_for_start=True)
    assert not gate.deciding() and gate.status() == {"started": False, "paused": False}
    assert gate.start() == "trial started" and gate.deciding()
    assert gate.start() == "the trial was already started"


def test_pause_and_resume():
    gate = OperatorGate()
    assert gate.pause(True) == "paused: no new goals" and not gate.deciding()
    assert gate.pause(True) == "already paused"
    assert gate.status() == {"started": True, "paused": True}
    assert gate.pause(False) == "resumed" and gate.deciding()
    assert gate.pause(False) == "was not paused"


def test_a_paused_trial_that_was_never_started_needs_both():
    gate = OperatorGate(wait_for_start=True)
    gate.pause(True)
    gate.start()
    assert not gate.deciding()
    gate.pause(False)
    assert gate.deciding()
