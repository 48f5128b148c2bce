"""Iterator: runs one contained state once per item of an iterable."""
from __future__ import annotations

import threading
import traceback
from typing import Any, Callable, Iterable, Optional, Sequence, Union

from smach import log
from smach.container import Container, ensure_state
from smach.exceptions import InvalidStateError, InvalidTransitionError, InvalidUserCodeError
from smach.state import State
from smach.user_data import UserData

__all__ = ["Iterator"]


class Iterator(Container):
    """Runs the contained state for each item of ``it``, with the item in ``userdata[it_label]``.

    Args:
        it: an iterable, or a callable returning one (called when the iterator starts).
        loop_outcomes: outcomes of the contained state that go on to the next item (if empty, every
            outcome not in ``break_outcomes`` loops).
        break_outcomes: outcomes that stop the loop; every outcome that does not loop stops it too.
        final_outcome_map: ``{state_outcome: container_outcome}`` applied to the outcome that stopped it.
        exhausted_outcome: the outcome when all items were used.

    .. note:: The contained state gets the iterator's own userdata (no remapping), as upstream.
       A preempt ends the loop with ``preempted`` (if registered) instead of upstream's habit of
       returning whatever the last item returned, which could be an unregistered loop outcome.
    """

    def __init__(self, outcomes: Sequence[str], input_keys: Sequence[str], output_keys: Sequence[str],
                 it: Union[Iterable, Callable[[], Iterable]] = (), it_label: str = "it_data",
                 exhausted_outcome: str = "exhausted") -> None:
        Container.__init__(self, outcomes, input_keys, output_keys)
        self._items = it
        self._items_label = it_label
        self._exhausted_outcome = exhausted_outcome
        self._state_label = ""
        self._state: Optional[State] = None
        self._loop_outcomes: list[str] = []
        self._break_outcomes: list[str] = []
        self._final_outcome_map: dict[str, str] = {}
        self._lock = threading.RLock()

    def set_iteritems(self, it: Union[Iterable, Callable[[], Iterable]], it_label: str = "it_data") -> None:
        self._items = it
        self._items_label = it_label

    @staticmethod
    def set_contained_state(label: str, state: State, loop_outcomes: Sequence[str] = (),
                            break_outcomes: Sequence[str] = (), final_outcome_map: Optional[dict] = None) -> State:
        """Set the state run for each item (call inside ``with iterator:``)."""
        self = Iterator._currently_opened_container()
        ensure_state(label, state)
        outcomes = state.get_registered_outcomes()
        for o in list(loop_outcomes) + list(break_outcomes):
            if o not in outcomes:
                raise InvalidTransitionError("Loop/break outcome '%s' is not an outcome of the contained state "
                                             "'%s' (%s)" % (o, label, outcomes))
        self._state_label = label
        self._state = state
        self._loop_outcomes = list(loop_outcomes)
        self._break_outcomes = list(break_outcomes)
        self._final_outcome_map = dict(final_outcome_map or {})
        return state

    # ---- structure ------------------------------------------------------------------------------
    def __getitem__(self, key: str) -> State:
        if key != self._state_label or self._state is None:
            raise KeyError("State '%s' not found in iterator" % key)
        return self._state

    def get_children(self) -> dict:
        return {} if self._state is None else {self._state_label: self._state}

    def set_initial_state(self, initial_states: Sequence[str], userdata: Optional[Any] = None) -> None:
        if userdata is not None:
            self.userdata.update(userdata)

    def get_initial_states(self) -> list:
        return [self._state_label] if self._state is not None else []

    def get_active_states(self) -> list:
        return [self._state_label] if self._is_running and self._state is not None else []

    def get_internal_edges(self) -> list:
        edges = [[o, self._state_label, self._state_label] for o in self._loop_outcomes]
        for o in self._state.get_registered_outcomes() if self._state is not None else []:
            if o in self._loop_outcomes:
                continue
            edges.append([o, self._state_label, self._map_outcome(o)])
        return edges

    def _map_outcome(self, outcome: str) -> str:
        return self._final_outcome_map.get(outcome, outcome)

    def check_consistency(self) -> None:
        if self._state is None:
            raise InvalidStateError("Iterator has no contained state (call Iterator.set_contained_state).")
        registered = self.get_registered_outcomes()
        if self._exhausted_outcome not in registered:
            raise InvalidTransitionError("Exhausted outcome '%s' is not an outcome of the iterator (%s)"
                                         % (self._exhausted_outcome, registered))
        for o in self._break_outcomes:
            if self._map_outcome(o) not in registered:
                raise InvalidTransitionError("Break outcome '%s' maps to '%s', not an outcome of the iterator (%s)"
                                             % (o, self._map_outcome(o), registered))

    # ---- execution ------------------------------------------------------------------------------
    def execute(self, parent_ud: Optional[Any] = None) -> str:
        if parent_ud is None:
            parent_ud = UserData()
        self.check_consistency()
        assert self._state is not None
        state = self._state
        with self._lock:
            self._is_running = True
        try:
            self._copy_input_keys(parent_ud, self.userdata)
            self.call_start_cbs()
            items = self._items() if callable(self._items) else self._items
            outcome = self._exhausted_outcome
            preempted = False
            for item in items:
                if log.is_shutdown():
                    break
                with self._lock:
                    if self._preempt_requested:
                        preempted = True
                        break
                log.loginfo("Iterating %s of %s" % (item, self._items))
                self.userdata[self._items_label] = item
                try:
                    outcome = state.execute(self.userdata)
                except InvalidUserCodeError:
                    log.logerr("Could not execute Iterator state '%s'" % self._state_label)
                    raise
                except Exception:
                    raise InvalidUserCodeError("Could not execute iterator state '%s' of type '%s': %s"
                                               % (self._state_label, state, traceback.format_exc())) from None
                if outcome not in state.get_registered_outcomes():
                    raise InvalidTransitionError("Iterator state '%s' returned unregistered outcome '%s'"
                                                 % (self._state_label, outcome))
                with self._lock:
                    if self._preempt_requested:
                        preempted = True
                        break
                loops = (outcome in self._loop_outcomes) if self._loop_outcomes else True
                if outcome in self._break_outcomes or not loops:
                    break
                self.call_transition_cbs()
                outcome = self._exhausted_outcome
            outcome = self._finish(outcome, preempted, state)
            self._copy_output_keys(self.userdata, parent_ud)
            self.call_termination_cbs([self._state_label], outcome)
            return outcome
        finally:
            with self._lock:
                self._is_running = False

    def _finish(self, outcome: str, preempted: bool, state: State) -> str:
        """Turn the last outcome into a registered container outcome, settling a preemption."""
        registered = self.get_registered_outcomes()
        if preempted:
            if state.preempt_requested():
                state.recall_preempt()
            self.service_preempt()
            mapped = self._map_outcome(outcome)
            if mapped in registered and outcome not in self._loop_outcomes and outcome != self._exhausted_outcome:
                return mapped
            if "preempted" in registered:
                return "preempted"
            log.logwarn("Iterator preempted but has no 'preempted' outcome; returning '%s'" % self._exhausted_outcome)
            return self._exhausted_outcome
        mapped = self._map_outcome(outcome)
        if mapped not in registered:
            raise InvalidTransitionError("Iterator stopped with outcome '%s' (mapped to '%s') which is not one of its "
                                         "outcomes %s" % (outcome, mapped, registered))
        return mapped

    # ---- preemption -----------------------------------------------------------------------------
    def request_preempt(self) -> None:
        with self._lock:
            self._preempt_requested = True
            if self._is_running and self._state is not None:
                self._state.request_preempt()

    def recall_preempt(self) -> None:
        with self._lock:
            self._preempt_requested = False
