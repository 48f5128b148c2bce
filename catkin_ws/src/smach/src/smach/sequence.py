"""Sequence: a StateMachine whose states run one after the other on a connector outcome."""
from __future__ import annotations

from typing import Optional, Sequence as Seq

from smach.state import State
from smach.state_machine import StateMachine

__all__ = ["Sequence"]


class Sequence(StateMachine):
    """A StateMachine where each added state's ``connector_outcome`` leads to the next state added.

    The last state's connector outcome falls through to the container outcome of the same name, so
    ``connector_outcome`` is usually also one of ``outcomes``.
    """

    def __init__(self, outcomes: Seq[str], connector_outcome: str, input_keys: Seq[str] = (),
                 output_keys: Seq[str] = ()) -> None:
        StateMachine.__init__(self, outcomes, input_keys, output_keys)
        self._last_added_seq_label: Optional[str] = None
        self._connector_outcome = connector_outcome

    @staticmethod
    def add(label: str, state: State, transitions: Optional[dict] = None,
            remapping: Optional[dict] = None) -> State:
        """Add the next state of the sequence (explicit ``transitions`` are kept for other outcomes)."""
        self = Sequence._currently_opened_container()
        prev = self._last_added_seq_label
        ret = StateMachine.add(label, state, transitions, remapping)
        if prev is not None:
            self._transitions[prev][self._connector_outcome] = label
        self._last_added_seq_label = label
        return ret
