"""UserData, the key/value store of a container, and Remapper, a state's restricted view of it."""
from __future__ import annotations

import copy
import threading
from typing import Any, Iterable, Mapping, Optional

from smach import log
from smach.exceptions import UndeclaredKeyError

__all__ = ["UserData", "Remapper", "Const", "get_const"]


class UserData:
    """A thread-safe key/value store with attribute and item access.

    The dict lives in ``_data`` (introspection and viewers read it). Reading a missing key raises
    ``KeyError`` (upstream behaviour), for attribute access too.
    """

    def __init__(self) -> None:
        self._data: dict[str, Any] = {}
        self._lock = threading.RLock()
        self.__initialized = True

    def update(self, other_userdata: Any) -> None:
        """Copy every key of another UserData (or a Remapper, or a mapping) into this one."""
        for key in list(other_userdata.keys()):
            self[key] = other_userdata[key]

    def extract(self, keys: Iterable[str], remapping: Mapping[str, str]) -> "UserData":
        """A new UserData with ``keys`` renamed by the reverse of ``remapping`` (upstream helper)."""
        reverse = {v: k for k, v in remapping.items()}
        if len(reverse) != len(remapping):
            log.logerr("SMACH userdata remapping is not one-to-one: " + str(remapping))
        ud = UserData()
        for key in keys:
            ud[reverse.get(key, key)] = copy.copy(self[key])
        return ud

    def merge(self, ud: "UserData", keys: Iterable[str], remapping: Mapping[str, str]) -> None:
        """Copy ``keys`` of ``ud`` into this store, renamed by ``remapping`` (upstream helper)."""
        for key in keys:
            self[remapping.get(key, key)] = copy.copy(ud[key])

    def keys(self) -> list:
        with self._lock:
            return list(self._data.keys())

    def __contains__(self, key: object) -> bool:
        return key in self._data

    def __getitem__(self, key: str) -> Any:
        with self._lock:
            try:
                return self._data[key]
            except KeyError:
                raise KeyError("Userdata key '%s' not available. Available keys are: %s"
                               % (key, list(self._data.keys()))) from None

    def __setitem__(self, key: str, item: Any) -> None:
        with self._lock:
            self._data[key] = item

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        return self[name]

    def __setattr__(self, name: str, value: Any) -> None:
        if name.startswith("_") or "_UserData__initialized" not in self.__dict__:
            object.__setattr__(self, name, value)
            return
        self[name] = value

    def __repr__(self) -> str:
        return "UserData(%r)" % (self._data,)

    # pickling/copying must not go through __getattr__/__setattr__ magic
    def __getstate__(self) -> dict:
        return {"_data": dict(self._data)}

    def __setstate__(self, state: dict) -> None:
        object.__setattr__(self, "_data", dict(state["_data"]))
        object.__setattr__(self, "_lock", threading.RLock())
        object.__setattr__(self, "_UserData__initialized", True)


class Const:
    """A read-only proxy of an input-only userdata value that has attributes of its own.

    Setting or deleting an attribute raises ``TypeError``; everything read through it is read-only too.
    """

    def __init__(self, obj: Any) -> None:
        object.__setattr__(self, "_obj", obj)

    def __getattr__(self, name: str) -> Any:
        return get_const(getattr(self._obj, name))

    def __getitem__(self, key: Any) -> Any:
        return get_const(self._obj[key])

    def __setattr__(self, name: str, value: Any) -> None:
        log.logerr("Attempting to set '%s' but this member is read-only." % name)
        raise TypeError("Attempting to set '%s' but this member is read-only." % name)

    def __delattr__(self, name: str) -> None:
        log.logerr("Attempting to delete '%s' but this member is read-only." % name)
        raise TypeError("Attempting to delete '%s' but this member is read-only." % name)

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self._obj(*args, **kwargs)

    def __len__(self) -> int:
        return len(self._obj)

    def __iter__(self):
        return (get_const(x) for x in self._obj)

    def __contains__(self, item: Any) -> bool:
        return item in self._obj

    def __eq__(self, other: Any) -> bool:
        return self._obj == (other._obj if isinstance(other, Const) else other)

    def __hash__(self) -> int:
        return hash(self._obj)

    def __repr__(self) -> str:
        return repr(self._obj)

    def __str__(self) -> str:
        return str(self._obj)


def get_const(obj: Any) -> Any:
    """Wrap objects with their own attributes in :class:`Const` (upstream rule); others are returned as is.

    Callables (bound methods, functions) are returned unwrapped so that calling methods keeps working.
    """
    if hasattr(obj, "__dict__") and not callable(obj):
        return Const(obj)
    return obj


class Remapper:
    """A state's view of its container's userdata: only declared keys, renamed through ``remapping``.

    Reading a key not declared as input raises :class:`smach.InvalidUserCodeError` (also a KeyError);
    writing one not declared as output is logged and ignored (upstream behaviour). Input-only values with
    attributes are returned read-only (:class:`Const`). Values are passed by reference.
    """

    def __init__(self, ud: Any, input_keys: Iterable[str] = (), output_keys: Iterable[str] = (),
                 remapping: Optional[Mapping[str, str]] = None) -> None:
        object.__setattr__(self, "_ud", ud)
        object.__setattr__(self, "_input", list(input_keys))
        object.__setattr__(self, "_output", list(output_keys))
        object.__setattr__(self, "_remap", dict(remapping or {}))

    def _remap_key(self, key: str) -> str:
        return self._remap.get(key, key)

    def _read(self, key: str) -> Any:
        if key not in self._input:
            raise UndeclaredKeyError(
                "Reading from SMACH userdata key '%s' but the only keys that were declared as input to "
                "this state were: %s. This key needs to be declared as input to this state." % (key, self._input))
        value = self._ud[self._remap_key(key)]
        if key not in self._output:
            return get_const(value)
        return value

    def _write(self, key: str, value: Any) -> None:
        if key not in self._output:
            log.logerr("Writing to SMACH userdata key '%s' but the only keys that were declared as output "
                       "from this state were: %s." % (key, self._output))
            return
        self._ud[self._remap_key(key)] = value

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        return self._read(name)

    def __setattr__(self, name: str, value: Any) -> None:
        if name.startswith("_"):
            object.__setattr__(self, name, value)
            return
        self._write(name, value)

    def __getitem__(self, key: str) -> Any:
        return self._read(key)

    def __setitem__(self, key: str, value: Any) -> None:
        self._write(key, value)

    def keys(self) -> list:
        """The state's own names of its declared input keys that exist in the parent userdata.

        Upstream returned the parent's names; these are the names the state can read back.
        """
        return [k for k in self._input if self._remap_key(k) in self._ud]

    def __contains__(self, key: object) -> bool:
        if key not in self._input and key not in self._output:
            return False
        return self._remap_key(key) in self._ud  # type: ignore[arg-type]

    def update(self, other_userdata: Any) -> None:
        """Write every key of ``other_userdata`` through this view (undeclared ones are refused)."""
        for key in list(other_userdata.keys()):
            self._write(key, other_userdata[key])

    def __repr__(self) -> str:
        return "Remapper(in=%s, out=%s, remap=%s)" % (self._input, self._output, self._remap)
