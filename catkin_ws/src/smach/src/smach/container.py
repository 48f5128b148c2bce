"""Container: a State holding child states, built inside ``with container:`` blocks."""
from __future__ import annotations

import threading
import traceback
from typing import Any, Callable, Optional, Sequence

from smach import log
from smach.exceptions import InvalidConstructionError, InvalidStateError
from smach.state import State
from smach.user_data import UserData
from smach.util import has_smach_interface

__all__ = ["Container"]


class Container(State):
    """Base class of StateMachine, Concurrence and Iterator.

    Holds its own ``userdata``; input keys are copied in from the parent's userdata when it starts and
    output keys are copied back when it ends. Start, transition and termination callbacks let
    introspection follow it.

    .. note:: ``with c:`` takes a global re-entrant construction lock so that the class-level ``add``
       functions know which container is open. Unlike upstream, the container is closed and the lock
       released even if the ``with`` block raises.
    """

    _construction_stack: list["Container"] = []
    _construction_lock = threading.RLock()
    _context_kwargs: list[dict] = []

    def __init__(self, outcomes: Sequence[str] = (), input_keys: Sequence[str] = (),
                 output_keys: Sequence[str] = ()) -> None:
        State.__init__(self, outcomes, input_keys, output_keys)
        self.userdata = UserData()
        self._start_cbs: list[tuple[Callable, list]] = []
        self._transition_cbs: list[tuple[Callable, list]] = []
        self._termination_cbs: list[tuple[Callable, list]] = []
        self._is_running = False

    # ---- structure (overridden) -----------------------------------------------------------------
    def __getitem__(self, key: str) -> State:
        raise NotImplementedError()

    def get_children(self) -> dict:
        """A dict label -> child state."""
        raise NotImplementedError()

    def set_initial_state(self, initial_states: Sequence[str], userdata: Optional[UserData] = None) -> None:
        raise NotImplementedError()

    def get_initial_states(self) -> list:
        raise NotImplementedError()

    def get_active_states(self) -> list:
        raise NotImplementedError()

    def get_internal_edges(self) -> list:
        """A list of [outcome, from_label, to_label] (to_label None: the outcome falls through)."""
        raise NotImplementedError()

    def check_consistency(self) -> None:
        raise NotImplementedError()

    def is_running(self) -> bool:
        return self._is_running

    # ---- construction ---------------------------------------------------------------------------
    def open(self) -> "Container":
        """Make this the container that ``add`` calls go to (re-entrant, takes the construction lock)."""
        Container._construction_lock.acquire()
        Container._construction_stack.append(self)
        Container._context_kwargs.append({})
        return self

    def close(self) -> None:
        """Stop adding to this container and release the construction lock."""
        try:
            if not Container._construction_stack or Container._construction_stack[-1] is not self:
                raise InvalidConstructionError("Attempting to close a container that is not currently open.")
            Container._construction_stack.pop()
            Container._context_kwargs.pop()
            self._close()
        finally:
            Container._construction_lock.release()

    def _close(self) -> None:
        """Hook for subclasses, called when the container is closed."""

    def opened(self, **kwargs: Any) -> "Container":
        """``with c.opened(**kwargs):`` opens the container with context arguments."""
        self.open()
        Container._context_kwargs[-1] = kwargs
        return self

    def __enter__(self) -> "Container":
        return self.open()

    def __exit__(self, exc_type: Any, exc_val: Any, exc_tb: Any) -> bool:
        if exc_type is not None:
            log.logerr("Error raised during SMACH container construction: \n"
                       + "".join(traceback.format_exception(exc_type, exc_val, exc_tb)))
        self.close()
        return False

    @classmethod
    def _currently_opened_container(cls) -> "Container":
        """The innermost open container; it must be an instance of ``cls``."""
        if not Container._construction_stack:
            raise InvalidConstructionError(
                "Attempting to access the currently opened container, but no container is opened.")
        top = Container._construction_stack[-1]
        if not isinstance(top, cls):
            raise InvalidConstructionError("The currently opened container is a %s, not a %s."
                                           % (type(top).__name__, cls.__name__))
        return top

    def is_opened(self) -> bool:
        return bool(Container._construction_stack) and Container._construction_stack[-1] is self

    def assert_opened(self, msg: str = "") -> None:
        if not self.is_opened():
            raise InvalidConstructionError(msg or "This container is not open.")

    # ---- userdata in and out --------------------------------------------------------------------
    def _copy_input_keys(self, parent_ud: Any, ud: UserData) -> None:
        if parent_ud is None:
            return
        for key in self.get_registered_input_keys():
            try:
                ud[key] = parent_ud[key]
            except KeyError:
                log.logwarn("Attempting to copy input key '%s', but this key does not exist." % key)

    def _copy_output_keys(self, ud: UserData, parent_ud: Any) -> None:
        if parent_ud is None:
            return
        for key in self.get_registered_output_keys():
            try:
                parent_ud[key] = ud[key]
            except KeyError:
                log.logwarn("Attempting to copy output key '%s', but this key does not exist." % key)

    # ---- callbacks ------------------------------------------------------------------------------
    def register_start_cb(self, start_cb: Callable, cb_args: Sequence[Any] = ()) -> None:
        """``start_cb(userdata, initial_states, *cb_args)`` is called when the container starts."""
        self._start_cbs.append((start_cb, list(cb_args)))

    def register_transition_cb(self, transition_cb: Callable, cb_args: Sequence[Any] = ()) -> None:
        """``transition_cb(userdata, active_states, *cb_args)`` is called on every transition."""
        self._transition_cbs.append((transition_cb, list(cb_args)))

    def register_termination_cb(self, termination_cb: Callable, cb_args: Sequence[Any] = ()) -> None:
        """``termination_cb(userdata, terminal_states, outcome, *cb_args)`` is called when it ends."""
        self._termination_cbs.append((termination_cb, list(cb_args)))

    def call_start_cbs(self) -> None:
        for cb, args in list(self._start_cbs):
            try:
                cb(self.userdata, self.get_initial_states(), *args)
            except Exception:
                log.logerr("Could not execute start callback: " + traceback.format_exc())

    def call_transition_cbs(self) -> None:
        for cb, args in list(self._transition_cbs):
            try:
                cb(self.userdata, self.get_active_states(), *args)
            except Exception:
                log.logerr("Could not execute transition callback: " + traceback.format_exc())

    def call_termination_cbs(self, terminal_states: Sequence[str], outcome: str) -> None:
        for cb, args in list(self._termination_cbs):
            try:
                cb(self.userdata, terminal_states, outcome, *args)
            except Exception:
                log.logerr("Could not execute termination callback: " + traceback.format_exc())


def ensure_state(label: str, state: Any) -> None:
    """Raise InvalidStateError unless ``state`` looks like a smach State (a common construction mistake)."""
    if not (has_smach_interface(state) and callable(getattr(state, "execute", None))):
        raise InvalidStateError("Attempting to add state '%s' which is not a smach.State but a %s."
                                % (label, type(state).__name__))
