"""State, the unit of work of a smach machine, and CBState, a state made from a plain callback."""
from __future__ import annotations

import functools
import threading
from typing import Any, Callable, Iterable, Optional, Sequence

from smach.util import has_smach_interface, unique_list

__all__ = ["State", "CBState", "CBInterface", "cb_interface"]


class State:
    """Base class of every smach state.

    A state declares the outcomes it may return and the userdata keys it reads (input), writes (output)
    or both (io); containers enforce the declaration through a :class:`smach.Remapper`. ``execute(ud)``
    does the work and returns one registered outcome.

    .. note:: Preemption is cooperative: ``request_preempt`` only raises a flag that ``execute`` should
       poll with ``preempt_requested()``; a state that honours it calls ``service_preempt()`` and
       returns its ``preempted`` outcome.
    """

    def __init__(self, outcomes: Sequence[str] = (), input_keys: Sequence[str] = (),
                 output_keys: Sequence[str] = (), io_keys: Sequence[str] = ()) -> None:
        # None is accepted for any list (some programs pass it)
        outcomes, input_keys, output_keys, io_keys = (outcomes or (), input_keys or (), output_keys or (),
                                                      io_keys or ())
        self._outcomes: list[str] = unique_list(outcomes)
        self._input_keys: list[str] = unique_list(list(input_keys) + list(io_keys))
        self._output_keys: list[str] = unique_list(list(output_keys) + list(io_keys))
        self._preempt_requested = False
        self._preempt_lock = threading.Lock()

    def execute(self, ud: Any) -> str:
        """Do the state's work and return an outcome (to be overridden)."""
        raise NotImplementedError()

    # ---- interface declaration ------------------------------------------------------------------
    def register_outcomes(self, new_outcomes: Iterable[str]) -> None:
        self._outcomes = unique_list(self._outcomes + list(new_outcomes))

    def get_registered_outcomes(self) -> tuple:
        return tuple(self._outcomes)

    def register_io_keys(self, keys: Iterable[str]) -> None:
        keys = list(keys)
        self.register_input_keys(keys)
        self.register_output_keys(keys)

    def register_input_keys(self, keys: Iterable[str]) -> None:
        self._input_keys = unique_list(self._input_keys + list(keys))

    def get_registered_input_keys(self) -> tuple:
        return tuple(self._input_keys)

    def register_output_keys(self, keys: Iterable[str]) -> None:
        self._output_keys = unique_list(self._output_keys + list(keys))

    def get_registered_output_keys(self) -> tuple:
        return tuple(self._output_keys)

    # ---- preemption -----------------------------------------------------------------------------
    def request_preempt(self) -> None:
        """Ask the state to stop as soon as it can."""
        self._preempt_requested = True

    def service_preempt(self) -> None:
        """Acknowledge a preempt request (the state is stopping because of it)."""
        self._preempt_requested = False

    def recall_preempt(self) -> None:
        """Withdraw a preempt request that was not serviced."""
        self._preempt_requested = False

    def preempt_requested(self) -> bool:
        return self._preempt_requested


class CBInterface:
    """A callable carrying a smach interface (outcomes and keys); what ``@cb_interface`` returns.

    It binds like a function when it decorates a method, so ``CBState(self.method)`` keeps the interface.
    """

    def __init__(self, cb: Callable, outcomes: Sequence[str] = (), input_keys: Sequence[str] = (),
                 output_keys: Sequence[str] = (), io_keys: Sequence[str] = ()) -> None:
        self._cb = cb
        self._outcomes = unique_list(outcomes)
        self._input_keys = unique_list(list(input_keys) + list(io_keys))
        self._output_keys = unique_list(list(output_keys) + list(io_keys))
        functools.update_wrapper(self, cb)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self._cb(*args, **kwargs)

    def __get__(self, obj: Any, objtype: Any = None) -> "CBInterface":
        if obj is None:
            return self
        return CBInterface(self._cb.__get__(obj, objtype), self._outcomes, self._input_keys,
                           self._output_keys)

    def get_registered_outcomes(self) -> list:
        return list(self._outcomes)

    def get_registered_input_keys(self) -> list:
        return list(self._input_keys)

    def get_registered_output_keys(self) -> list:
        return list(self._output_keys)


class cb_interface:  # noqa: N801 (upstream name)
    """Decorator declaring the smach interface of a callback: ``@cb_interface(outcomes=[...], ...)``.

    Unlike upstream, ``io_keys`` are kept (upstream drops them).
    """

    def __init__(self, outcomes: Sequence[str] = (), input_keys: Sequence[str] = (),
                 output_keys: Sequence[str] = (), io_keys: Sequence[str] = ()) -> None:
        self._outcomes = list(outcomes)
        self._input_keys = list(input_keys) + list(io_keys)
        self._output_keys = list(output_keys) + list(io_keys)

    def __call__(self, cb: Callable) -> CBInterface:
        return CBInterface(cb, self._outcomes, self._input_keys, self._output_keys)


class CBState(State):
    """A state whose ``execute`` calls ``cb(ud, *cb_args, **cb_kwargs)`` and returns its result.

    If ``cb`` carries an interface (``@cb_interface``) its outcomes and keys are added to the state's.
    """

    def __init__(self, cb: Callable, cb_args: Sequence[Any] = (), cb_kwargs: Optional[dict] = None,
                 outcomes: Sequence[str] = (), input_keys: Sequence[str] = (),
                 output_keys: Sequence[str] = (), io_keys: Sequence[str] = ()) -> None:
        State.__init__(self, outcomes, input_keys, output_keys, io_keys)
        self._cb = cb
        self._cb_args = list(cb_args)
        self._cb_kwargs = dict(cb_kwargs or {})
        if has_smach_interface(cb):
            self.register_input_keys(cb.get_registered_input_keys())
            self.register_output_keys(cb.get_registered_output_keys())
            self.register_outcomes(cb.get_registered_outcomes())

    def execute(self, ud: Any) -> str:
        return self._cb(ud, *self._cb_args, **self._cb_kwargs)
