"""Encoding of userdata in introspection messages, and safe decoding of what comes from the network.

Status messages carry ``local_data = base64(pickle.dumps(userdata._data, 2))`` as text, because that
is what every SMACH viewer reads. Unpickling what arrives from the network would let any node run code in
ours, so decoding here never calls a class or function named by the data, unless the caller opts in
(``allow_unsafe=True``, the upstream behaviour):

* text starting with ``{`` is read as a JSON object;
* otherwise it is base64 pickle, read by :class:`SafeUnpickler`: plain builtin data (dict, list, tuple,
  str, bytes, int, float, bool, None, set, frozenset, complex) comes back as such; every other class
  becomes an inert :class:`Opaque` record of its name and state, so nothing outside this module runs.

Decoding is bounded (see the limits below): payload size, nesting depth, number of values (counted with
a memo of visited objects, so shared references cannot make it exponential), distinct class names per
payload, and the stand-in classes kept between payloads. Past a limit a :class:`DecodeError` names it.

Pure Python (no ROS import) so that the viewer and the tests can use it directly.
"""
from __future__ import annotations

import base64
import binascii
import io
import itertools
import json
import math
import pickle
import threading
from collections import OrderedDict
from typing import Any, Iterable, Optional

__all__ = ["encode_local_data", "decode_local_data", "SafeUnpickler", "Opaque", "to_plain",
           "contains_opaque", "check_limits", "DecodeError", "MAX_LOCAL_DATA_CHARS", "MAX_DEPTH", "MAX_VALUES",
           "MAX_CLASSES_PER_PAYLOAD", "MAX_CACHED_CLASSES", "MAX_VALUE_BYTES"]

# Limits on what comes from the network. Past any of them decoding fails with a DecodeError that names it.
MAX_LOCAL_DATA_CHARS = 8 * 1024 * 1024  # text size (memory bomb guard)
MAX_DEPTH = 50                # nesting of containers (dict/list/tuple/set/Opaque state)
MAX_VALUES = 200000           # values reached, counting shared references once per path (DAG bombs)
MAX_CLASSES_PER_PAYLOAD = 64  # distinct non-builtin class names one payload may name
MAX_CACHED_CLASSES = 512      # Opaque stand-in classes kept between payloads (least recently used dropped)
MAX_NAME_CHARS = 200          # a module or class name longer than this is refused
# Limit on what we send: a userdata value whose pickle is bigger is summarised instead (one key must not
# turn every status message of a container into megabytes).
MAX_VALUE_BYTES = 256 * 1024


class DecodeError(ValueError):
    """The local_data text is neither a JSON object nor a readable base64 pickle of a dict, or it exceeds
    one of the limits above."""


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


# One stand-in class per dotted name (pickle's NEWOBJ needs a real class); bounded LRU so that a stream of
# payloads naming ever new classes cannot grow memory without end.
_opaque_classes: "OrderedDict[str, type]" = OrderedDict()
_opaque_lock = threading.Lock()


def _opaque_class(module: str, name: str) -> type:
    qual = "%s.%s" % (module, name)
    with _opaque_lock:
        cls = _opaque_classes.get(qual)
        if cls is not None:
            _opaque_classes.move_to_end(qual)
            return cls
        cls = type("Opaque[%s]" % qual, (Opaque,), {"_qualname": qual})
        _opaque_classes[qual] = cls
        while len(_opaque_classes) > MAX_CACHED_CLASSES:
            _opaque_classes.popitem(last=False)
        return cls


def _latin1_encode(text: str, encoding: str = "latin1") -> bytes:
    """What protocol-2 pickles of bytes call (``_codecs.encode(text, 'latin1')``), and nothing else."""
    if not isinstance(text, str) or encoding not in ("latin1", "latin-1"):
        raise pickle.UnpicklingError("refused codec call")
    return text.encode("latin1")


def _bytes_like(kind: type) -> Any:
    """``bytes``/``bytearray`` for the unpickler, refusing a size argument (``bytes(10**10)`` is a memory
    bomb of a few bytes)."""
    def build(*args: Any) -> Any:
        if args and not isinstance(args[0], (bytes, bytearray, str)):
            raise pickle.UnpicklingError("refused %s(%s)" % (kind.__name__, type(args[0]).__name__))
        return kind(*args)
    return build


# Protocol-2 pickles name builtins by their Python 2 module '__builtin__' (find_class sees the raw name).
_SAFE_GLOBALS = {(module, name): value
                 for module in ("builtins", "__builtin__")
                 for name, value in (("set", set), ("frozenset", frozenset), ("complex", complex),
                                     ("bytearray", _bytes_like(bytearray)), ("bytes", _bytes_like(bytes)))}
_SAFE_GLOBALS[("_codecs", "encode")] = _latin1_encode


class SafeUnpickler(pickle.Unpickler):
    """An Unpickler that only ever builds plain data and :class:`Opaque` records, naming at most
    ``MAX_CLASSES_PER_PAYLOAD`` distinct classes."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._names: set = set()

    def find_class(self, module: str, name: str) -> Any:
        safe = _SAFE_GLOBALS.get((module, name))
        if safe is not None:
            return safe
        if len(module) > MAX_NAME_CHARS or len(name) > MAX_NAME_CHARS:
            raise pickle.UnpicklingError("class name longer than %d characters" % MAX_NAME_CHARS)
        self._names.add((module, name))
        if len(self._names) > MAX_CLASSES_PER_PAYLOAD:
            raise pickle.UnpicklingError("more than %d distinct classes named" % MAX_CLASSES_PER_PAYLOAD)
        return _opaque_class(module, name)


def encode_local_data(data: dict, exclude: Iterable[str] = (), max_value_bytes: int = MAX_VALUE_BYTES) -> str:
    """``base64(pickle protocol 2)`` of a userdata dict. Never raises.

    Keys in ``exclude`` are left out (upstream #18); a value that cannot be pickled (a lock, a Popen, a
    SWIG object: upstream #18, #77) or whose pickle exceeds ``max_value_bytes`` is replaced by a short text
    saying so, so one bad key never stops the container's status (nor the machine's transitions).
    """
    excluded = set(exclude)
    data = {k: v for k, v in list(dict(data).items()) if k not in excluded}
    try:
        raw = pickle.dumps(data, 2)
        if len(raw) <= max_value_bytes:
            return base64.b64encode(raw).decode("ascii")
    except Exception:  # noqa: BLE001 - anything a user object's reduce may raise
        pass
    safe = {}
    for key, value in data.items():
        safe_key = key if isinstance(key, (str, int, float, bool, type(None))) else _short_repr(key)
        try:
            size = len(pickle.dumps(value, 2))
        except Exception:  # noqa: BLE001
            safe[safe_key] = "<unpicklable %s: %s>" % (type(value).__name__, _short_repr(value))
            continue
        if size > max_value_bytes:
            safe[safe_key] = "<%s of %d pickled bytes, over the %d-byte cap: not sent>" % (
                type(value).__name__, size, max_value_bytes)
        else:
            safe[safe_key] = value
    try:
        raw = pickle.dumps(safe, 2)
    except Exception as ex:  # noqa: BLE001 - a value changed under us between the two dumps
        raw = pickle.dumps({"__error__": "userdata could not be encoded: %s" % _short_repr(ex)}, 2)
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
        except (ValueError, RecursionError) as ex:
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
    check_limits(data)
    return data


_CONTAINERS = (dict, list, tuple, set, frozenset)
_LEAVES = (str, int, float, bool, type(None), bytes, bytearray, complex)
_LEAF_TYPES = frozenset(_LEAVES)  # exact types: a fast test in the hot loops


def _children(obj: Any) -> Optional[Iterable]:
    """The values directly inside a decoded container (None for a leaf)."""
    if isinstance(obj, dict):
        return itertools.chain(obj.keys(), obj.values())
    if isinstance(obj, (list, tuple, set, frozenset)):
        return obj
    if isinstance(obj, Opaque):
        return (obj.state, obj.args)
    return None


def check_limits(data: Any, max_depth: int = MAX_DEPTH, max_values: int = MAX_VALUES) -> None:
    """Raise DecodeError if decoded data nests deeper than ``max_depth`` or holds more than ``max_values``
    values. Linear in the payload: each container is expanded once (a memo of visited objects), so shared
    references (a 444-byte pickle can describe a DAG of 2**45 paths) cost nothing."""
    seen: set = set()
    stack = [(data, 0)]
    count = 0
    while stack:
        obj, depth = stack.pop()
        if id(obj) in seen:
            continue
        seen.add(id(obj))
        if isinstance(obj, dict):
            count += 2 * len(obj)
            inner = [c for c in itertools.chain(obj.keys(), obj.values()) if type(c) not in _LEAF_TYPES]
        elif isinstance(obj, (list, tuple, set, frozenset)):
            count += len(obj)
            inner = [c for c in obj if type(c) not in _LEAF_TYPES]
        elif isinstance(obj, Opaque):
            count += 2
            inner = [obj.state, obj.args]
        else:
            continue
        if count > max_values:
            raise DecodeError("local_data holds more than %d values" % max_values)
        if inner:
            if depth + 1 >= max_depth:
                raise DecodeError("local_data nests deeper than %d levels" % max_depth)
            stack.extend((child, depth + 1) for child in inner)


def contains_opaque(obj: Any) -> bool:
    """True if decoded data holds an :class:`Opaque` (a class the safe decoder refused) anywhere.
    Iterative with a memo of visited containers: linear, whatever the sharing or cycles."""
    seen: set = set()
    stack = [obj]
    while stack:
        item = stack.pop()
        if isinstance(item, Opaque):
            return True
        if id(item) in seen:
            continue
        seen.add(id(item))
        inner = _children(item)
        if inner is not None:
            stack.extend(child for child in inner if not isinstance(child, _LEAVES))
    return False


def to_plain(obj: Any, max_depth: int = 30, max_values: int = 20000) -> Any:
    """Turn decoded userdata into JSON-serialisable values for display (never raises).

    Bounded: past ``max_depth`` levels a value shows as ``"..."``, a cycle as ``"<cycle>"``, and once
    ``max_values`` values were emitted the rest show as ``"<truncated>"`` (shared references make the
    JSON form of a small payload exponentially large)."""
    return _plain(obj, 0, max_depth, [max_values], set())


def _plain(obj: Any, depth: int, max_depth: int, budget: list, path: set) -> Any:
    budget[0] -= 1
    if budget[0] < 0:
        return "<truncated>"
    if obj is None or isinstance(obj, (bool, int, str)):
        return obj
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else str(obj)
    if isinstance(obj, (bytes, bytearray)):
        return "<%d bytes>" % len(obj) if len(obj) > 64 else repr(bytes(obj))
    if isinstance(obj, complex):
        return str(obj)
    if not isinstance(obj, _CONTAINERS) and not isinstance(obj, Opaque):
        return _short_repr(obj)
    if depth > max_depth:
        return "..."
    if id(obj) in path:
        return "<cycle>"
    path.add(id(obj))
    depth += 1
    try:
        if isinstance(obj, dict):
            return {str(k): _plain(v, depth, max_depth, budget, path) for k, v in obj.items()}
        if isinstance(obj, _CONTAINERS):
            return [_plain(v, depth, max_depth, budget, path) for v in obj]
        out: dict[str, Any] = {"__class__": obj._qualname}
        state = obj.state
        if isinstance(state, tuple) and len(state) == 2 and (state[0] is None or isinstance(state[0], dict)) \
                and (state[1] is None or isinstance(state[1], dict)):
            merged = dict(state[0] or {})
            merged.update(state[1] or {})
            state = merged
        if state is not None:
            out["state"] = _plain(state, depth, max_depth, budget, path)
        elif obj.args:
            out["args"] = _plain(list(obj.args), depth, max_depth, budget, path)
        return out
    finally:
        path.discard(id(obj))
