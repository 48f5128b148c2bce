"""StateMachine: runs one child state at a time and follows the transition table."""
from __future__ import annotations

import threading
import traceback
from typing import Any, Optional, Sequence

from smach import log
from smach.container import Container, ensure_state
from smach.exceptions import (InvalidStateError, InvalidTransitionError, InvalidUserCodeError)
from smach.state import State
from smach.user_data import Remapper, UserData

__all__ = ["StateMachine"]


class StateMachine(Container):
    """A finite state machine of child states.

    ``execute`` starts at the initial state (the first one added unless set), runs it with a
    :class:`smach.Remapper` of the machine's userdata, and follows ``transitions[outcome]``: to another
    state, or to a container outcome, which ends the machine. An outcome with no transition falls through
    as the container outcome of the same name.

    .. note:: Preemption: ``request_preempt`` is forwarded to the running child (or to the next child
       if it arrives between two states). A child that clears the request (``service_preempt``)
       ends the preemption; if it ignores it, the next child is preempted too. All of it happens under
       one lock, so a request can never fall between two states.
    """

    def __init__(self, outcomes: Sequence[str], input_keys: Sequence[str] = (),
                 output_keys: Sequence[str] = ()) -> None:
        Container.__init__(self, outcomes, input_keys, output_keys)
        self._state_transitioning_lock = threading.RLock()
        self._states: dict[str, State] = {}
        self._transitions: dict[str, dict[str, Optional[str]]] = {}
        self._remappings: dict[str, dict[str, str]] = {}
        self._initial_state_label: Optional[str] = None
        self._current_label: Optional[str] = None
        self._current_state: Optional[State] = None
        self._current_transitions: Optional[dict] = None
        self._preempted_label: Optional[str] = None
        self._preempted_state: Optional[State] = None
        self._last_added_label: Optional[str] = None
        self._connector_outcomes: list[str] = []

    # ---- construction ---------------------------------------------------------------------------
    @staticmethod
    def add(label: str, state: State, transitions: Optional[dict] = None,
            remapping: Optional[dict] = None) -> State:
        """Add a state to the open StateMachine (the first added is the initial state)."""
        self = StateMachine._currently_opened_container()
        log.logdebug("Adding state (%s, %s, %s)" % (label, state, transitions))
        ensure_state(label, state)
        transitions = dict(transitions or {})
        remapping = dict(remapping or {})
        if label in self._states:
            raise InvalidStateError("Attempting to add state with label '%s' to state machine, but this label "
                                    "is already being used." % label)
        if label in self.get_registered_outcomes():
            raise InvalidStateError("Attempting to add state with label '%s' to state machine, but this label "
                                    "is already a container outcome." % label)
        self.check_state_spec(label, state, transitions)
        if self._initial_state_label is None:
            self._initial_state_label = label
        for outcome in state.get_registered_outcomes():
            transitions.setdefault(outcome, None)
        # connect the state added by add_auto before this one
        if self._last_added_label is not None:
            prev = self._transitions[self._last_added_label]
            for outcome in self._connector_outcomes:
                if prev.get(outcome) is None:
                    prev[outcome] = label
            self._last_added_label = None
            self._connector_outcomes = []
        self._states[label] = state
        self._transitions[label] = transitions
        self._remappings[label] = remapping
        return state

    @staticmethod
    def add_auto(label: str, state: State, connector_outcomes: Sequence[str],
                 transitions: Optional[dict] = None, remapping: Optional[dict] = None) -> State:
        """Add a state whose ``connector_outcomes`` lead to the next state added (unless given here)."""
        self = StateMachine._currently_opened_container()
        registered = state.get_registered_outcomes()
        missing = [o for o in connector_outcomes if o not in registered]
        if missing:
            raise InvalidStateError("Attempting to auto-connect states with outcomes %s, but state '%s' only "
                                    "has registered outcomes: %s" % (list(connector_outcomes), label, registered))
        ret = StateMachine.add(label, state, transitions, remapping)
        self._last_added_label = label
        self._connector_outcomes = list(connector_outcomes)
        return ret

    @staticmethod
    def check_state_spec(label: str, state: State, transitions: dict) -> None:
        """Raise InvalidTransitionError if a transition is given for an outcome the state does not have."""
        registered = state.get_registered_outcomes()
        for outcome in transitions:
            if outcome not in registered:
                raise InvalidTransitionError(
                    "Specified outcome '%s' on state '%s', which only has available registered outcomes: %s"
                    % (outcome, label, registered))

    def check_consistency(self) -> None:
        """Raise InvalidTransitionError if the initial state or a transition target does not exist."""
        available = set(self._states) | set(self.get_registered_outcomes())
        errors = ""
        if self._initial_state_label is None:
            errors += "\n\tNo initial state set."
        elif self._initial_state_label not in self._states:
            errors += "\n\tInitial state label: '%s' is not in the state machine." % self._initial_state_label
        for label, state in self._states.items():
            transitions = self._transitions[label]
            try:
                self.check_state_spec(label, state, transitions)
            except InvalidTransitionError as ex:
                errors += "\n\t" + str(ex)
            for outcome, target in transitions.items():
                if target is not None and target not in available:
                    errors += "\n\tState '%s' references unknown state '%s'" % (label, target)
        if errors:
            raise InvalidTransitionError("State machine failed consistency check: " + errors
                                         + "\n\n\tAvailable states: " + str(sorted(available)))

    # ---- structure ------------------------------------------------------------------------------
    def __getitem__(self, key: str) -> State:
        if key not in self._states:
            raise KeyError("State '%s' not found in state machine '%s'" % (key, self))
        return self._states[key]

    def __contains__(self, key: str) -> bool:
        return key in self._states

    def get_children(self) -> dict:
        return self._states

    def set_initial_state(self, initial_states: Sequence[str], userdata: Optional[Any] = None) -> None:
        """Start at ``initial_states[0]`` and add ``userdata`` to the machine's userdata.

        The label may name a state that is added later (as upstream): ``execute`` checks it.
        """
        if len(initial_states) > 1:
            raise InvalidStateError("Cannot set more than one initial state for a SMACH state machine.")
        if initial_states:
            self._initial_state_label = initial_states[0]
        if userdata is not None:
            self.userdata.update(userdata)

    def get_initial_states(self) -> list:
        return [] if self._initial_state_label is None else [self._initial_state_label]

    def get_active_states(self) -> list:
        label = self._current_label
        return [] if label is None else [str(label)]

    def get_internal_edges(self) -> list:
        return [[outcome, from_label, to_label]
                for from_label, transitions in self._transitions.items()
                for outcome, to_label in transitions.items()]

    def is_running(self) -> bool:
        return self._is_running

    # ---- execution ------------------------------------------------------------------------------
    def _set_current_state(self, label: Optional[str]) -> None:
        if label is None:
            self._current_label, self._current_state, self._current_transitions = None, None, None
        else:
            self._current_label = label
            self._current_state = self._states[label]
            self._current_transitions = self._transitions[label]

    def execute(self, parent_ud: Optional[Any] = None) -> Optional[str]:
        """Run the machine to a container outcome (None if the process shuts down first)."""
        if parent_ud is None:
            parent_ud = UserData()
        with self._state_transitioning_lock:
            self.check_consistency()
            self._is_running = True
            try:
                self._preempted_label = None
                self._preempted_state = None
                self._set_current_state(self._initial_state_label)
                self._copy_input_keys(parent_ud, self.userdata)
                log.loginfo("State machine starting in initial state '%s' with userdata: \n\t%s"
                            % (self._current_label, list(self.userdata.keys())))
                self.call_start_cbs()
                container_outcome = None
                while container_outcome is None and not log.is_shutdown():
                    container_outcome = self._update_once()
                self._copy_output_keys(self.userdata, parent_ud)
            finally:
                self._set_current_state(None)
                self._is_running = False
        return container_outcome

    def _update_once(self) -> Optional[str]:
        """Run the current state once and transition; returns a container outcome or None."""
        last_label = self._current_label
        state = self._current_state
        assert state is not None and last_label is not None
        if self._preempt_requested:
            if self._preempted_state is not None:
                if self._preempted_state.preempt_requested():
                    log.loginfo("Last state '%s' did not service preempt. Preempting next state '%s' before "
                                "executing..." % (self._preempted_label, last_label))
                    self._preempt_current_state()
                else:
                    self._preempt_requested = False
                    self._preempted_state = None
                    self._preempted_label = None
            else:
                self._preempt_current_state()
        remapper = Remapper(self.userdata, state.get_registered_input_keys(),
                            state.get_registered_output_keys(), self._remappings[last_label])
        self._state_transitioning_lock.release()
        try:
            outcome = state.execute(remapper)
        except InvalidUserCodeError:
            log.logerr("State '%s' failed to execute." % last_label)
            raise
        except Exception:
            raise InvalidUserCodeError("Could not execute state '%s' of type '%s': %s"
                                       % (last_label, state, traceback.format_exc())) from None
        finally:
            self._state_transitioning_lock.acquire()

        if outcome not in state.get_registered_outcomes():
            raise InvalidTransitionError(
                "Attempted to return outcome '%s' from state '%s' of type '%s' which only has registered "
                "outcomes: %s" % (outcome, last_label, state, state.get_registered_outcomes()))
        transitions = self._current_transitions or {}
        if outcome not in transitions:
            raise InvalidTransitionError("Outcome '%s' of state '%s' is not bound to any transition target. "
                                         "Bound transitions include: %s" % (outcome, last_label, transitions))
        target = transitions[outcome]
        if target in self._states:
            self._set_current_state(target)
            log.loginfo("State machine transitioning '%s':'%s'-->'%s'" % (last_label, outcome, target))
            self.call_transition_cbs()
            return None
        if target is None:
            target = outcome
        if target not in self.get_registered_outcomes():
            raise InvalidTransitionError(
                "Outcome '%s' of state '%s' with transition target '%s' is neither a registered state nor a "
                "registered container outcome." % (outcome, last_label, target))
        # terminal: settle the preemption bookkeeping
        if self._preempt_requested and self._preempted_state is not None:
            if not self._preempted_state.preempt_requested():
                self.service_preempt()
            else:
                self._preempted_state.recall_preempt()
        self._preempted_state = None
        self._preempted_label = None
        self._set_current_state(None)
        log.loginfo("State machine terminating '%s':'%s':'%s'" % (last_label, outcome, target))
        self.call_termination_cbs([last_label], target)
        return target

    # ---- preemption -----------------------------------------------------------------------------
    def _preempt_current_state(self) -> None:
        """Forward the preempt to the current child (it may not be executing yet).

        A child that already got a preempt is asked again: it may have serviced the last request, and
        this one is new (upstream #88 skipped it, so the next state never saw the second preempt).
        """
        if self._current_state is None:
            return
        if self._preempted_state is not None and self._preempted_state is not self._current_state:
            self._preempted_state.recall_preempt()
        self._preempted_state = self._current_state
        self._preempted_label = self._current_label
        try:
            self._preempted_state.request_preempt()
        except Exception:
            log.logerr("Failed to preempt contained state '%s': %s" % (self._preempted_label, traceback.format_exc()))

    def request_preempt(self) -> None:
        with self._state_transitioning_lock:
            self._preempt_requested = True
            if self._current_state is not None:
                self._preempt_current_state()

    def recall_preempt(self) -> None:
        with self._state_transitioning_lock:
            self._preempt_requested = False
            if self._preempted_state is not None:
                self._preempted_state.recall_preempt()
                self._preempted_state = None
                self._preempted_label = None
