"""Encoding of userdata in introspection messages, and safe decoding of what comes from the network.

Status messages carry ``local_data = base64(pickle.dumps(userdata._data, 2))`` as text, because that
is what every SMACH viewer reads. Unpickling what arrives from the network would let any node run code in
ours, so decoding here never calls a class or function named by the data, unless the caller opts in
(``allow_unsafe=True``, the upstream behaviour):

* text starting with ``{`` is read as a JSON object;
* otherwise it is base64 pickle, read by :class:`SafeUnpickler`: plain builtin data (dict, list, tuple,
  str, bytes, int, float, bool, None, set, frozenset, complex) comes back as such; every other class
  becomes an inert :class:`Opaque` record of its name and state, so nothing outside this module runs.

Pure Python (no ROS import) so that the viewer and the tests can use it directly.
"""
from __future__ import annotations

import base64
import binascii
import io
import json
import math
import pickle
from typing import Any

__all__ = ["encode_local_data", "decode_local_data", "SafeUnpickler", "Opaque", "to_plain",
           "contains_opaque", "DecodeError", "MAX_LOCAL_DATA_CHARS"]

MAX_LOCAL_DATA_CHARS = 8 * 1024 * 1024  # refuse bigger payloads (memory bomb guard)


class DecodeError(ValueError):
    """The local_data text is neither a JSON object nor a readable base64 pickle of a dict."""


class Opaque:
    """An inert stand-in for an object of a class the safe decoder refused to load.

    Holds the class's dotted name, the constructor arguments and the pickled state, so a viewer can show
    them; it has no behaviour of its own.
    """

    _qualname = "?"

    def __new__(cls, *args: Any, **kwargs: Any) -> "Opaque":
        obj = object.__new__(cls)
        obj.args = args
        obj.state = None
        return obj

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args = args

    def __setstate__(self, state: Any) -> None:
        self.state = state

    def __repr__(self) -> str:
        return "<%s %r>" % (self._qualname, self.state if self.state is not None else self.args)


_opaque_classes: dict[str, type] = {}


def _opaque_class(module: str, name: str) -> type:
    qual = "%s.%s" % (module, name)
    cls = _opaque_classes.get(qual)
    if cls is None:
        cls = type("Opaque[%s]" % qual, (Opaque,), {"_qualname": qual})
        _opaque_classes[qual] = cls
    return cls


def _latin1_encode(text: str, encoding: str = "latin1") -> bytes:
    """What protocol-2 pickles of bytes call (``_codecs.encode(text, 'latin1')``), and nothing else."""
    if encoding not in ("latin1", "latin-1"):
        raise pickle.UnpicklingError("refused codec %r" % encoding)
    return text.encode("latin1")


_SAFE_GLOBALS = {
    ("builtins", "set"): set, ("builtins", "frozenset"): frozenset, ("builtins", "complex"): complex,
    ("builtins", "bytearray"): bytearray, ("__builtin__", "set"): set, ("__builtin__", "frozenset"): frozenset,
    ("_codecs", "encode"): _latin1_encode, ("builtins", "bytes"): bytes,
}


class SafeUnpickler(pickle.Unpickler):
    """An Unpickler that only ever builds plain data and :class:`Opaque` records."""

    def find_class(self, module: str, name: str) -> Any:
        safe = _SAFE_GLOBALS.get((module, name))
        if safe is not None:
            return safe
        return _opaque_class(module, name)


def encode_local_data(data: dict) -> str:
    """``base64(pickle protocol 2)`` of a userdata dict; values that cannot be pickled become their repr."""
    data = dict(data)
    try:
        raw = pickle.dumps(data, 2)
    except Exception:  # noqa: BLE001 - anything a user object's reduce may raise
        safe = {}
        for key, value in data.items():
            try:
                pickle.dumps(value, 2)
                safe[key] = value
            except Exception:  # noqa: BLE001
                safe[key] = "<unpicklable %s: %s>" % (type(value).__name__, _short_repr(value))
        raw = pickle.dumps(safe, 2)
    return base64.b64encode(raw).decode("ascii")


def _short_repr(value: Any, limit: int = 200) -> str:
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001
        text = object.__repr__(value)
    return text if len(text) <= limit else text[:limit] + "..."


def decode_local_data(text: str, allow_unsafe: bool = False) -> dict:
    """Decode ``local_data`` (JSON object or base64 pickle) into a dict; see the module docstring."""
    if text is None or text == "":
        return {}
    if len(text) > MAX_LOCAL_DATA_CHARS:
        raise DecodeError("local_data too large (%d chars)" % len(text))
    stripped = text.lstrip()
    if stripped.startswith("{"):
        try:
            data = json.loads(stripped)
        except ValueError as ex:
            raise DecodeError("local_data is not valid JSON: %s" % ex) from None
    else:
        try:
            raw = base64.b64decode(text.encode("ascii") if isinstance(text, str) else text, validate=False)
        except (binascii.Error, ValueError, UnicodeEncodeError) as ex:
            raise DecodeError("local_data is not base64: %s" % ex) from None
        try:
            if allow_unsafe:
                data = pickle.loads(raw)
            else:
                data = SafeUnpickler(io.BytesIO(raw)).load()
        except Exception as ex:  # noqa: BLE001 - malformed pickles raise many kinds
            raise DecodeError("local_data is not a readable pickle: %s" % ex) from None
    if not isinstance(data, dict):
        raise DecodeError("local_data must hold a dict, got %s" % type(data).__name__)
    return data


def contains_opaque(obj: Any, _depth: int = 0) -> bool:
    """True if decoded data holds an :class:`Opaque` (a class the safe decoder refused) anywhere."""
    if _depth > 50:
        return True
    if isinstance(obj, Opaque):
        return True
    if isinstance(obj, dict):
        return any(contains_opaque(k, _depth + 1) or contains_opaque(v, _depth + 1) for k, v in obj.items())
    if isinstance(obj, (list, tuple, set, frozenset)):
        return any(contains_opaque(v, _depth + 1) for v in obj)
    return False


def to_plain(obj: Any, _depth: int = 0) -> Any:
    """Turn decoded userdata into JSON-serialisable values for display (never raises)."""
    if _depth > 30:
        return "..."
    if obj is None or isinstance(obj, (bool, int, str)):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else str(obj)
    if isinstance(obj, (bytes, bytearray)):
        return "<%d bytes>" % len(obj) if len(obj) > 64 else repr(bytes(obj))
    if isinstance(obj, dict):
        return {str(k): to_plain(v, _depth + 1) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [to_plain(v, _depth + 1) for v in obj]
    if isinstance(obj, complex):
        return str(obj)
    if isinstance(obj, Opaque):
        out: dict[str, Any] = {"__class__": obj._qualname}
        state = obj.state
        if isinstance(state, tuple) and len(state) == 2 and (state[0] is None or isinstance(state[0], dict)):
            merged = dict(state[0] or {})
            merged.update(state[1] or {})
            state = merged
        if state is not None:
            out["state"] = to_plain(state, _depth + 1)
        elif obj.args:
            out["args"] = to_plain(list(obj.args), _depth + 1)
        return out
    return _short_repr(obj)
