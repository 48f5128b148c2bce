"""Concurrence: runs all its children at once, each in its own thread."""
from __future__ import annotations

import copy
import threading
import traceback
from typing import Any, Callable, Optional, Sequence

from smach import log
from smach.container import Container, ensure_state
from smach.exceptions import InvalidStateError, InvalidTransitionError, InvalidUserCodeError
from smach.state import State
from smach.user_data import Remapper, UserData

__all__ = ["Concurrence"]


class Concurrence(Container):
    """Runs every child concurrently and maps their outcomes to one container outcome.

    Args:
        outcomes: the container's outcomes.
        default_outcome: returned when no ``outcome_map`` entry matches and ``outcome_cb`` gives none.
        outcome_map: ``{container_outcome: {child_label: child_outcome, ...}}``; an entry matches when
            every listed child ended with the listed outcome; the most specific matching entry (most
            children listed) wins, ties go to the first entry.
        outcome_cb: ``outcome_cb(child_outcomes) -> outcome or None``, overrides the map.
        child_termination_cb: ``cb(child_outcomes) -> bool`` called each time a child ends; True
            preempts the children still running; otherwise the container waits for all of them.

    .. note:: The container waits on a condition with a predicate, so a preempt request or a child
       ending can never be lost however they interleave (upstream could miss both).
    """

    def __init__(self, outcomes: Sequence[str], default_outcome: str, input_keys: Sequence[str] = (),
                 output_keys: Sequence[str] = (), outcome_map: Optional[dict] = None,
                 outcome_cb: Optional[Callable] = None, child_termination_cb: Optional[Callable] = None) -> None:
        Container.__init__(self, outcomes, input_keys, output_keys)
        outcome_map = dict(outcome_map or {})
        errors = ""
        if not isinstance(default_outcome, str):
            errors += "\n\tDefault outcome '%s' does not appear to be a string." % (default_outcome,)
        elif default_outcome not in outcomes:
            errors += "\n\tDefault outcome '%s' is unregistered." % default_outcome
        for o in outcome_map:
            if o not in outcomes:
                errors += "\n\tUnregistered outcome '%s' in and outcome_map." % o
        if outcome_cb is not None and not callable(outcome_cb):
            errors += "\n\tOutcome callback '%s' is not callable." % outcome_cb
        if child_termination_cb is not None and not callable(child_termination_cb):
            errors += "\n\tChild termination callback '%s' is not callable." % child_termination_cb
        if errors:
            raise InvalidStateError("Errors specifying outcome policy of concurrence: %s" % errors)
        self._default_outcome = default_outcome
        self._outcome_map = outcome_map
        self._outcome_cb = outcome_cb
        self._child_termination_cb = child_termination_cb
        self._states: dict[str, State] = {}
        self._remappings: dict[str, dict] = {}
        self._threads: dict[str, threading.Thread] = {}
        self._child_outcomes: dict[str, Optional[str]] = {}
        self._done_cond = threading.Condition(threading.RLock())
        self._terminate = False
        self._user_code_exception: Optional[str] = None
        self._forwarded: set[str] = set()  # children that got this container's preempt request

    # ---- construction ---------------------------------------------------------------------------
    @staticmethod
    def add(label: str, state: State, remapping: Optional[dict] = None) -> State:
        """Add a child state to the open Concurrence."""
        self = Concurrence._currently_opened_container()
        ensure_state(label, state)
        if label in self._states:
            raise InvalidStateError("Attempting to add state with label '%s' to concurrence, but this label is "
                                    "already being used." % label)
        self._states[label] = state
        self._remappings[label] = dict(remapping or {})
        return state

    def check_consistency(self) -> None:
        """Raise InvalidTransitionError if the outcome map names unknown children or outcomes."""
        errors = ""
        for container_outcome, conditions in self._outcome_map.items():
            for label, outcome in conditions.items():
                if label not in self._states:
                    errors += "\n\toutcome_map['%s'] names unknown child '%s'" % (container_outcome, label)
                elif outcome not in self._states[label].get_registered_outcomes():
                    errors += ("\n\toutcome_map['%s'] expects outcome '%s' of child '%s', which only has %s"
                               % (container_outcome, outcome, label,
                                  self._states[label].get_registered_outcomes()))
        if errors:
            raise InvalidTransitionError("Concurrence failed consistency check: " + errors)

    # ---- structure ------------------------------------------------------------------------------
    def __getitem__(self, key: str) -> State:
        if key not in self._states:
            raise KeyError("State '%s' not found in concurrence" % key)
        return self._states[key]

    def get_children(self) -> dict:
        return self._states

    def set_initial_state(self, initial_states: Sequence[str], userdata: Optional[Any] = None) -> None:
        if initial_states:
            log.logwarn("Attempting to set initial states in Concurrence container, but Concurrence children "
                        "are always all executed initially.")
        if userdata is not None:
            self.userdata.update(userdata)

    def get_initial_states(self) -> list:
        return list(self._states.keys())

    def get_active_states(self) -> list:
        with self._done_cond:
            return [label for label, outcome in self._child_outcomes.items() if outcome is None]

    def get_internal_edges(self) -> list:
        edges = []
        for container_outcome, conditions in self._outcome_map.items():
            for label, outcome in conditions.items():
                edges.append([outcome, label, container_outcome])
        return edges

    # ---- execution ------------------------------------------------------------------------------
    def execute(self, parent_ud: Optional[Any] = None) -> str:
        if parent_ud is None:
            parent_ud = UserData()
        if not self._states:
            # (upstream 2.5.2 raises too; before that it waited forever for children that never end)
            raise InvalidStateError("Concurrence has no child states to execute.")
        self.check_consistency()
        with self._done_cond:
            self._is_running = True
            self._terminate = False
            self._user_code_exception = None
            self._forwarded = set()
            self._child_outcomes = {label: None for label in self._states}
            if self._preempt_requested:
                # passed on before the start (upstream #37 ignored it): every child starts preempted
                self._forward_preempt()
        try:
            self._copy_input_keys(parent_ud, self.userdata)
            log.loginfo("Concurrence starting with userdata: \n\t%s" % list(self.userdata.keys()))
            self.call_start_cbs()
            self._threads = {label: threading.Thread(name="concurrent_split:" + label, target=self._state_runner,
                                                     args=(label,), daemon=True)
                             for label in self._states}
            for thread in self._threads.values():
                thread.start()
            with self._done_cond:
                self._done_cond.wait_for(lambda: self._terminate or self._preempt_requested
                                         or all(o is not None for o in self._child_outcomes.values()))
                running = [label for label, o in self._child_outcomes.items() if o is None]
                if self._preempt_requested:
                    self._forwarded.update(running)
                if running:
                    log.logdebug("SMACH Concurrence preempting running states: %s" % running)
                    for label in running:
                        self._states[label].request_preempt()
            for thread in self._threads.values():
                while thread.is_alive():
                    thread.join(0.1)
                    if log.is_shutdown():
                        break
            if self._user_code_exception is not None:
                raise InvalidUserCodeError("A concurrent state raised an exception during execution: "
                                           + self._user_code_exception)
            with self._done_cond:
                forwarded = set(self._forwarded)
                preempted = self._preempt_requested
            children_serviced = self._recall_unserviced(running, forwarded)
            outcomes = dict(self._child_outcomes)
            log.loginfo("Concurrent Outcomes: " + str(outcomes))
            if preempted and "preempted" in self.get_registered_outcomes():
                # the container honours its parent's preempt itself, whatever its children did and
                # however late the request came (upstream #98 returned the mapped outcome)
                log.loginfo("Concurrence preempted: outcome 'preempted'.")
                self.service_preempt()
                outcome = "preempted"
            else:
                if preempted and forwarded and children_serviced:
                    log.loginfo("Concurrence serviced preempt.")
                    self.service_preempt()
                elif preempted:
                    # nobody serviced it (e.g. every child had already ended, upstream #53): the flag
                    # stays and the parent passes it on
                    log.loginfo("Concurrence preempted but not serviced; leaving it to the parent.")
                outcome = self._decide_outcome(outcomes)
            self.call_termination_cbs(list(self._states.keys()), outcome)
            self._copy_output_keys(self.userdata, parent_ud)
            return outcome
        finally:
            self._threads = {}
            with self._done_cond:
                self._is_running = False

    def _recall_unserviced(self, running: list, forwarded: set) -> bool:
        """Withdraw the preempt requests that children did not service (they must be reusable); returns
        whether every child that got the container's own preempt serviced it."""
        serviced = True
        for label in set(running) | forwarded:
            if self._states[label].preempt_requested():
                if label in forwarded:
                    serviced = False
                    log.logwarn("State '%s' in concurrence did not service preempt." % label)
                self._states[label].recall_preempt()
        return serviced

    def _decide_outcome(self, outcomes: dict) -> str:
        """Apply outcome_map (most specific match), then outcome_cb, else the default outcome."""
        outcome = self._default_outcome
        best = -1
        for container_outcome, conditions in self._outcome_map.items():
            if all(outcomes.get(label) == expected for label, expected in conditions.items()):
                if len(conditions) > best:
                    best, outcome = len(conditions), container_outcome
        if self._outcome_cb is not None:
            try:
                cb_outcome = self._outcome_cb(copy.copy(outcomes))
            except Exception:
                raise InvalidUserCodeError("Could not execute outcome callback '%s': %s"
                                           % (self._outcome_cb, traceback.format_exc())) from None
            if cb_outcome is not None:
                if isinstance(cb_outcome, str):
                    outcome = cb_outcome
                else:
                    log.logerr("Outcome callback returned a non-string '%s', using outcome '%s'"
                               % (cb_outcome, outcome))
        if outcome not in self.get_registered_outcomes():
            raise InvalidTransitionError("Concurrence outcome '%s' is not one of its registered outcomes %s"
                                         % (outcome, self.get_registered_outcomes()))
        return outcome

    def _state_runner(self, label: str) -> None:
        """Thread body: run one child, record its outcome, wake the container."""
        state = self._states[label]
        self.call_transition_cbs()
        try:
            outcome = state.execute(Remapper(self.userdata, state.get_registered_input_keys(),
                                             state.get_registered_output_keys(), self._remappings[label]))
            if outcome is None or outcome not in state.get_registered_outcomes():
                raise InvalidTransitionError("Concurrent state '%s' returned outcome '%s' which is not one of its "
                                             "registered outcomes %s" % (label, outcome,
                                                                         state.get_registered_outcomes()))
        except Exception:
            with self._done_cond:
                self._user_code_exception = "child '%s': %s" % (label, traceback.format_exc())
                self._child_outcomes[label] = "__exception__"
                self._terminate = True
                self._done_cond.notify_all()
            return
        log.loginfo("Concurrent state '%s' returned outcome '%s' on termination." % (label, outcome))
        with self._done_cond:
            self._child_outcomes[label] = outcome
            preempt_others = False
            if self._child_termination_cb is not None:
                try:
                    preempt_others = bool(self._child_termination_cb(dict(self._child_outcomes)))
                except Exception:
                    self._user_code_exception = ("child termination callback: " + traceback.format_exc())
                    preempt_others = True
            if preempt_others:
                self._terminate = True
            self._done_cond.notify_all()
        self.call_transition_cbs()

    # ---- preemption -----------------------------------------------------------------------------
    def request_preempt(self) -> None:
        """Preempt the container: every child still running is asked to stop."""
        with self._done_cond:
            self._preempt_requested = True
            if self._is_running:
                self._forward_preempt()
            self._done_cond.notify_all()

    def _forward_preempt(self) -> None:
        """Pass this container's preempt to every child still running that has not had it (lock held)."""
        for label, outcome in self._child_outcomes.items():
            if outcome is None and label not in self._forwarded:
                self._forwarded.add(label)
                self._states[label].request_preempt()

    def recall_preempt(self) -> None:
        with self._done_cond:
            self._preempt_requested = False
            for label in self._forwarded:
                if self._states[label].preempt_requested():
                    self._states[label].recall_preempt()
