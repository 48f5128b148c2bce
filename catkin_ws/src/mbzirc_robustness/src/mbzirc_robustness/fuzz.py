"""Malformed-message generator: given a ROS message (or service request) class, make bad instances.

Why: every node of the system must survive whatever arrives on its inputs (a flaky Wi-Fi link, a
sensor driver bug, another team's tool). This module is pure (genpy only, no master, no rospy) so its
cases are reproducible from a seed and testable in milliseconds; ``fuzz_runner`` sends them on a live graph.

Every case is delivered as wire bytes (``FuzzCase.payload``) so that one raw publisher per topic can send
both well-typed-but-absurd messages (NaN, inf, empty or mismatched arrays, empty images, wrong encodings,
huge values, empty or huge strings) and bytes that do not even deserialize (random, truncated).
"""
from __future__ import annotations

import copy
import io
import math
import random
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator

import genpy
from genmsg.msgs import parse_type

from mbzirc_robustness import constants as C

Path = tuple  # tuple of str (field name) or int (array index)

INT_RANGES: dict[str, tuple[int, int]] = {
    "int8": (-2**7, 2**7 - 1), "uint8": (0, 2**8 - 1), "byte": (-2**7, 2**7 - 1), "char": (0, 2**8 - 1),
    "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1),
    "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1),
}
FLOAT_VALUES: dict[str, list[float]] = {
    "float32": [math.nan, math.inf, -math.inf, 3.4e38, -3.4e38],
    "float64": [math.nan, math.inf, -math.inf, 1.7e308, -1.7e308],
}
BAD_STRINGS: list[tuple[str, str]] = [
    ("empty", ""),
    ("huge", "x" * C.HUGE_STRING_LEN),
    ("unknown_name", "no_such_robot_4242"),
    ("unicode", "\u00fcnkn\u00f6wn_\u540d\u524d/../\u0000"),
    ("whitespace", "  \t\n "),
]
BAD_ENCODINGS = ["", "bogus_encoding", "rgb8", "bgr8", "mono8", "16UC1", "32FC1", "64FC4"]


@dataclass
class FuzzCase:
    """One malformed input: a human label, its wire bytes, and whether it is well-typed.

    Args:
        label: what is wrong with it, e.g. ``"pose.position.x=nan"``; goes into the report.
        payload: the serialized message exactly as it goes on the wire.
        typed: True when ``payload`` deserializes into the target class (content is bad, framing is
            good); False for raw byte garbage, which the receiver's deserializer must reject.
    """

    label: str
    payload: bytes
    typed: bool = True


@dataclass
class GeneratorStats:
    """Counts kept by ``generate_cases`` so a caller can say what it skipped and why."""

    candidates: int = 0
    unserializable: int = 0
    errors: list[str] = field(default_factory=list)


# ---------------------------------------------------------------------------------------------------
# message introspection helpers
# ---------------------------------------------------------------------------------------------------
def message_class(type_name: str) -> type:
    """Class of a message type name such as ``geometry_msgs/Point`` (``Header`` means std_msgs's)."""
    if type_name == "Header":
        type_name = "std_msgs/Header"
    cls = genpy.message.get_message_class(type_name)
    if cls is None:
        raise ValueError(f"unknown message type {type_name!r}")
    return cls


def is_primitive(base: str) -> bool:
    """True for ROS built-in field types (numbers, bool, string, time, duration)."""
    return base in INT_RANGES or base in FLOAT_VALUES or base in ("bool", "string", "time", "duration")


def populated(cls: type, depth: int = 0) -> genpy.Message:
    """A valid instance of ``cls`` whose variable arrays hold one element (so nested leaves exist),
    strings hold a plausible id and headers the global frame: the template the mutations start from.

    .. note:: without this, an ``ObjectDetectionList`` has no objects and most of its leaves could
       never be mutated.
    """
    msg = cls()
    if depth > C.MAX_DEPTH:
        return msg
    for name, slot_type in zip(cls.__slots__, cls._slot_types):
        base, is_array, length = parse_type(slot_type)
        if is_primitive(base):
            if is_array and length is None and base not in ("uint8", "char"):
                setattr(msg, name, [_plain_value(base)])
            elif not is_array and base in ("time", "string"):
                setattr(msg, name, _plain_value(base))
            continue
        sub = message_class(base)
        if is_array:
            n = length if length is not None else 1
            setattr(msg, name, [populated(sub, depth + 1) for _ in range(n)])
        else:
            setattr(msg, name, populated(sub, depth + 1))
    if cls._type == "std_msgs/Header":
        msg.frame_id = C.TEMPLATE_FRAME  # so that the receiver's TF lookups succeed and bad values go deeper
    return msg


def _plain_value(base: str) -> Any:
    """A harmless value of a primitive type (element of a populated array)."""
    if base in FLOAT_VALUES:
        return 1.0
    if base == "string":
        return C.TEMPLATE_STRING
    if base == "bool":
        return False
    if base == "time":
        return genpy.Time(1, 0)
    if base == "duration":
        return genpy.Duration(1, 0)
    return 1


@dataclass
class Leaf:
    """A field reachable in an instance: its path, its base type, array-ness and fixed length."""

    path: Path
    base: str
    is_array: bool
    length: int | None


def leaves(msg: genpy.Message, prefix: Path = ()) -> Iterator[Leaf]:
    """Every primitive field or primitive array in ``msg`` (recursing into sub-messages and arrays)."""
    for name, slot_type in zip(msg.__slots__, msg._slot_types):
        base, is_array, length = parse_type(slot_type)
        path = prefix + (name,)
        if is_primitive(base):
            yield Leaf(path, base, is_array, length)
            continue
        value = getattr(msg, name)
        if is_array:
            yield Leaf(path, base, True, length)  # the array of sub-messages itself
            for i, item in enumerate(value):
                yield from leaves(item, path + (i,))
        else:
            yield from leaves(value, path)


def submessages(msg: genpy.Message, prefix: Path = ()) -> Iterator[tuple[Path, genpy.Message]]:
    """Every sub-message of ``msg`` with its path, ``msg`` itself first (path ``()``)."""
    yield prefix, msg
    for name, slot_type in zip(msg.__slots__, msg._slot_types):
        base, is_array, _ = parse_type(slot_type)
        if is_primitive(base):
            continue
        value = getattr(msg, name)
        if is_array:
            for i, item in enumerate(value):
                yield from submessages(item, prefix + (name, i))
        else:
            yield from submessages(value, prefix + (name,))


def get_path(msg: Any, path: Path) -> Any:
    """Value at ``path`` (field names and list indices)."""
    for p in path:
        msg = msg[p] if isinstance(p, int) else getattr(msg, p)
    return msg


def set_path(msg: Any, path: Path, value: Any) -> None:
    """Set the value at ``path``; ``path`` must not be empty."""
    parent = get_path(msg, path[:-1])
    if isinstance(path[-1], int):
        parent[path[-1]] = value
    else:
        setattr(parent, path[-1], value)


def path_str(path: Path) -> str:
    """``('objects', 0, 'pose')`` -> ``objects[0].pose``."""
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out or "<msg>"


def serialize(msg: genpy.Message) -> bytes:
    """Wire bytes of ``msg`` (raises on values genpy cannot pack)."""
    buff = io.BytesIO()
    msg.serialize(buff)
    return buff.getvalue()


# ---------------------------------------------------------------------------------------------------
# mutations
# ---------------------------------------------------------------------------------------------------
Mutation = tuple[str, Callable[[genpy.Message], None]]


def leaf_mutations(leaf: Leaf) -> list[Mutation]:
    """Bad values for one primitive field or array, each as (label, in-place mutator)."""
    p, name = leaf.path, path_str(leaf.path)
    out: list[Mutation] = []

    def setter(value: Any) -> Callable[[genpy.Message], None]:
        return lambda m: set_path(m, p, copy.copy(value))

    if leaf.is_array and not is_primitive(leaf.base):  # array of sub-messages
        if leaf.length is None:
            out.append((f"{name}=[]", setter([])))
            sub = message_class(leaf.base)
            out.append((f"{name}=[{C.MANY_ELEMENTS}x default]",
                        lambda m: set_path(m, p, [sub() for _ in range(C.MANY_ELEMENTS)])))
        return out
    if leaf.is_array:
        if leaf.base in ("uint8", "char"):
            fixed = leaf.length
            if fixed is None:
                out.append((f"{name}=b''", setter(b"")))
                out.append((f"{name}=13 random bytes", setter(bytes(range(13)))))
                out.append((f"{name}={C.HUGE_BYTES} bytes", setter(b"\xff" * C.HUGE_BYTES)))
            else:
                out.append((f"{name}=all 0xff", setter(b"\xff" * fixed)))
            return out
        n = leaf.length
        if n is None:
            out.append((f"{name}=[]", setter([])))
            for k in C.ODD_LENGTHS:
                out.append((f"{name}=len {k}", setter([_plain_value(leaf.base)] * k)))
            out.append((f"{name}=len {C.HUGE_ARRAY}", setter([_plain_value(leaf.base)] * C.HUGE_ARRAY)))
            n = C.ODD_LENGTHS[-1]
        for label, v in _scalar_values(leaf.base):
            out.append((f"{name}=[{label}]*{n}", setter([v] * n)))
        return out
    for label, v in _scalar_values(leaf.base):
        out.append((f"{name}={label}", setter(v)))
    return out


def _scalar_values(base: str) -> list[tuple[str, Any]]:
    """(label, value) pairs of extreme values of a primitive type."""
    if base in FLOAT_VALUES:
        return [(repr(v), v) for v in FLOAT_VALUES[base]]
    if base in INT_RANGES:
        lo, hi = INT_RANGES[base]
        return [(str(lo), lo), (str(hi), hi)]
    if base == "bool":
        return [("True", True)]
    if base == "string":
        return list(BAD_STRINGS)
    if base == "time":
        return [("t=0", genpy.Time(0, 0)), ("t=max", genpy.Time(2**32 - 1, 999_999_999))]
    if base == "duration":
        return [("d=min", genpy.Duration(-2**31, 0)), ("d=max", genpy.Duration(2**31 - 1, 999_999_999))]
    return []


def semantic_mutations(path: Path, sub: genpy.Message) -> list[Mutation]:
    """Type-aware bad contents for well-known message types (images, multi-arrays, scans, poses)."""
    t = sub._type
    name = path_str(path)
    out: list[Mutation] = []

    def edit(**fields: Any) -> Callable[[genpy.Message], None]:
        def apply(m: genpy.Message) -> None:
            target = get_path(m, path) if path else m
            for k, v in fields.items():
                setattr(target, k, copy.copy(v))
        return apply

    if t == "sensor_msgs/Image":
        out += [
            (f"{name}: empty image 0x0", edit(height=0, width=0, step=0, data=b"", encoding="rgb8")),
            (f"{name}: 480x640 bgr8 header but no data", edit(height=480, width=640, step=1920,
                                                             encoding="bgr8", data=b"")),
            (f"{name}: data shorter than height*step", edit(height=32, width=32, step=96, encoding="rgb8",
                                                            data=b"\x10" * 100)),
            (f"{name}: step smaller than width", edit(height=2, width=32, step=1, encoding="rgb8",
                                                      data=b"\x10" * 2)),
            (f"{name}: huge dims, tiny data", edit(height=2**31, width=2**31, step=2**32 - 1,
                                                   encoding="mono8", data=b"\x00" * 8)),
        ]
        for enc in BAD_ENCODINGS:
            out.append((f"{name}: 4x4 with encoding {enc!r}", edit(height=4, width=4, step=4, encoding=enc,
                                                                    data=b"\x00" * 16)))
    elif t == "sensor_msgs/CompressedImage":
        out += [(f"{name}: empty compressed", edit(format="jpeg", data=b"")),
                (f"{name}: garbage jpeg", edit(format="jpeg", data=b"\xff\xd8garbage")),
                (f"{name}: bogus format", edit(format="bogus", data=b"\x00" * 16))]
    elif t.startswith("std_msgs/") and t.endswith("MultiArray"):
        dim_cls = message_class("std_msgs/MultiArrayDimension")
        bad_dim = [dim_cls(label="rows", size=32, stride=1024), dim_cls(label="cols", size=32, stride=32)]
        val = 1.0 if "Float" in t else 1
        out += [
            (f"{name}: layout 32x32 but 1023 values", edit(data=[val] * 1023, layout=_layout(sub, bad_dim))),
            (f"{name}: layout 32x32 but 1025 values", edit(data=[val] * 1025, layout=_layout(sub, bad_dim))),
            (f"{name}: no data", edit(data=[])),
            (f"{name}: 1 value", edit(data=[val])),
        ]
        if "Float" in t:
            out.append((f"{name}: 1024 NaN", edit(data=[math.nan] * 1024)))
            out.append((f"{name}: 1024 inf", edit(data=[math.inf] * 1024)))
    elif t == "sensor_msgs/LaserScan":
        out += [
            (f"{name}: no ranges", edit(ranges=[], intensities=[])),
            (f"{name}: 719 ranges for a 720-beam scan", edit(angle_min=-math.pi, angle_max=math.pi,
                                                             angle_increment=2 * math.pi / 720,
                                                             ranges=[5.0] * 719)),
            (f"{name}: angle_increment 0", edit(angle_increment=0.0, ranges=[5.0] * 720)),
            (f"{name}: all-NaN ranges", edit(ranges=[math.nan] * 720)),
            (f"{name}: range_min > range_max", edit(range_min=30.0, range_max=0.1, ranges=[5.0] * 720)),
        ]
    elif t == "sensor_msgs/CameraInfo":
        out += [(f"{name}: K all zero (fx=0)", edit(K=[0.0] * 9, P=[0.0] * 12, width=640, height=480)),
                (f"{name}: K NaN", edit(K=[math.nan] * 9, width=640, height=480)),
                (f"{name}: zero size", edit(width=0, height=0))]
    elif t == "geometry_msgs/Quaternion":
        out += [(f"{name}: zero quaternion", edit(x=0.0, y=0.0, z=0.0, w=0.0)),
                (f"{name}: non-unit quaternion", edit(x=10.0, y=0.0, z=0.0, w=10.0))]
    elif t == "std_msgs/Header":
        out += [(f"{name}: unknown frame", edit(frame_id="no_such_frame")),
                (f"{name}: stamp far future", edit(stamp=genpy.Time(2**32 - 1, 0)))]
    return out


def _layout(sub: genpy.Message, dims: list) -> Any:
    """A MultiArrayLayout with ``dims`` (its class comes from the instance, whatever the array type)."""
    lay = copy.deepcopy(sub.layout)
    lay.dim = copy.deepcopy(dims)
    lay.data_offset = 0
    return lay


def global_mutations(msg: genpy.Message) -> list[Mutation]:
    """Whole-message mutations: every float NaN / inf, every string empty, every array empty."""
    all_leaves = list(leaves(msg))

    def fill(pred: Callable[[Leaf], bool], value_of: Callable[[Leaf], Any]) -> Callable[[genpy.Message], None]:
        def apply(m: genpy.Message) -> None:
            # deepest paths first so that emptying an array does not invalidate later paths
            for lf in sorted(all_leaves, key=lambda lf: -len(lf.path)):
                if pred(lf):
                    try:
                        set_path(m, lf.path, value_of(lf))
                    except (IndexError, AttributeError):
                        pass
        return apply

    def floats(value: float) -> Callable[[Leaf], Any]:
        return lambda lf: ([value] * (lf.length or len(get_path(msg, lf.path)) or 1)) if lf.is_array else value

    is_float = lambda lf: lf.base in FLOAT_VALUES  # noqa: E731
    return [
        ("all floats NaN", fill(is_float, floats(math.nan))),
        ("all floats +inf", fill(is_float, floats(math.inf))),
        ("all floats -inf", fill(is_float, floats(-math.inf))),
        ("all strings empty", fill(lambda lf: lf.base == "string" and not lf.is_array, lambda lf: "")),
        ("all variable arrays empty", fill(lambda lf: lf.is_array and lf.length is None,
                                           lambda lf: b"" if lf.base in ("uint8", "char") else [])),
    ]


def single_field_mutations(msg: genpy.Message) -> list[Mutation]:
    """One non-finite value in one float field, the rest valid: the case a node's whole-message checks miss
    (e.g. a pose whose x alone is NaN). Up to C.SINGLE_FIELD_FLOATS fields, alternating NaN and +inf; in an
    array only the first element is changed."""
    out: list[Mutation] = []
    floats = [lf for lf in leaves(msg) if lf.base in FLOAT_VALUES]
    for k, lf in enumerate(floats[: C.SINGLE_FIELD_FLOATS]):
        value, label = (math.nan, "NaN") if k % 2 == 0 else (math.inf, "+inf")
        name, p = path_str(lf.path), lf.path

        def apply(m: genpy.Message, p=p, value=value, lf=lf) -> None:
            if lf.is_array:
                arr = list(get_path(m, p)) or [0.0]
                arr[0] = value
                set_path(m, p, arr)
            else:
                set_path(m, p, value)
        out.append((f"only {name}{'[0]' if lf.is_array else ''}={label}", apply))
    return out


def raw_cases(cls: type, rng: random.Random) -> list[FuzzCase]:
    """Byte-level garbage with the right md5: random bytes, truncated and padded valid messages."""
    valid = serialize(populated(cls))
    out = [FuzzCase("raw: 0 bytes", b"", typed=False),
           FuzzCase("raw: 7 random bytes", bytes(rng.randrange(256) for _ in range(7)), typed=False),
           FuzzCase("raw: 64 random bytes", bytes(rng.randrange(256) for _ in range(64)), typed=False),
           FuzzCase("raw: length prefix 0xffffffff", b"\xff\xff\xff\xff" * 4, typed=False)]
    if len(valid) > 1:
        out.append(FuzzCase("raw: valid message truncated by half", valid[: len(valid) // 2], typed=False))
    return out


def generate_cases(cls: type, max_cases: int = C.DEFAULT_MAX_CASES, seed: int = 0,
                   include_raw: bool = True, stats: GeneratorStats | None = None) -> list[FuzzCase]:
    """Malformed instances of message class ``cls`` (also works for a service's request class).

    Args:
        cls: a genpy message class, e.g. ``sensor_msgs.msg.Image`` or ``CheckFireRequest``.
        max_cases: upper bound on the number of cases; semantic and whole-message cases are kept
            first, then a seeded sample of per-field cases.
        seed: the same seed gives the same cases.
        include_raw: add byte-level garbage (does not deserialize) after the typed cases.
        stats: if given, filled with what was generated and skipped.

    Returns:
        cases whose ``payload`` is ready to write on the wire; typed ones all deserialize into ``cls``.
    """
    stats = stats if stats is not None else GeneratorStats()
    rng = random.Random(seed)
    base = populated(cls)
    priority: list[Mutation] = []
    for path, sub in submessages(base):
        priority += semantic_mutations(path, sub)
    # whole-message and single-field non-finite values take turns, so that even a small budget sends both
    whole, single = global_mutations(base), single_field_mutations(base)
    for k in range(max(len(whole), len(single))):
        priority += whole[k:k + 1] + single[k:k + 1]
    leaf_list = list(leaves(base))
    rng.shuffle(leaf_list)
    leaf_list.sort(key=lambda lf: len(lf.path))  # stable: top-level fields (ids, names) first
    per_leaf = [leaf_mutations(lf) for lf in leaf_list]
    for muts in per_leaf:
        rng.shuffle(muts)
    # round robin over fields: every field gets one bad value before any field gets a second one
    per_field: list[Mutation] = [muts[i] for i in range(max(map(len, per_leaf), default=0))
                                 for muts in per_leaf if i < len(muts)]
    raws = raw_cases(cls, rng) if include_raw else []
    budget_typed = max(0, max_cases - min(len(raws), max(1, max_cases // 5)))
    out: list[FuzzCase] = [FuzzCase("default instance (all zero)", serialize(cls()))] if budget_typed else []
    seen = {c.payload for c in out}
    for label, mutate in priority + per_field:
        if len(out) >= budget_typed:
            break
        stats.candidates += 1
        msg = copy.deepcopy(base)
        try:
            mutate(msg)
            payload = serialize(msg)
        except Exception as exc:  # genpy refuses to pack it: cannot go on the wire as a typed message
            stats.unserializable += 1
            stats.errors.append(f"{label}: {type(exc).__name__}: {exc}")
            continue
        if payload not in seen:  # e.g. "all floats NaN" of a message without floats
            seen.add(payload)
            out.append(FuzzCase(label, payload))
    raws = [r for r in raws if r.payload not in seen]
    out += raws[: max(0, max_cases - len(out))]
    return out


# ---------------------------------------------------------------------------------------------------
# crafted pickles for SMACH introspection servers
# ---------------------------------------------------------------------------------------------------
SMACH_INIT_TYPE = "smach_msgs/SmachContainerInitialStatusCmd"


def pickle_marker_path(tag: str) -> str:
    """The file the code-running pickles would create: it must never exist after they were sent."""
    import os
    import tempfile
    return os.path.join(tempfile.gettempdir(), f"{C.PICKLE_MARKER_PREFIX}{tag}")


def _b64(raw: bytes) -> str:
    import base64
    return base64.b64encode(raw).decode("ascii")


def _global(module: str, name: str) -> bytes:
    return b"c" + module.encode() + b"\n" + name.encode() + b"\n"


def _short_str(text: str) -> bytes:
    data = text.encode()
    return b"X" + len(data).to_bytes(4, "little") + data


def crafted_pickles(marker: str) -> list[tuple[str, str]]:
    """(label, local_data) of pickles that a trusting unpickler (``pickle.loads``) would suffer.

    - code: a pickle whose load calls ``os.system`` / ``builtins.exec`` to create ``marker`` (the runner
      checks the file never appears: the receiver ran no code of ours);
    - huge: a payload past any sane size (``C.HUGE_PICKLE_CHARS`` of base64), and a reference bomb (a few
      hundred bytes naming 2^60 values through shared lists);
    - deep: 100 000 nested lists (a recursive reader overflows its stack);
    - truncated: half of a valid pickle, and text that is not base64 at all.
    Each is a dict at the top, as ``local_data`` must be, so that only the content is wrong.
    """
    import pickle
    proto = b"\x80\x02"
    key = _short_str("fuzz")

    def in_dict(value: bytes) -> bytes:
        return proto + b"}" + key + value + b"s."

    system = in_dict(_global("os", "system") + _short_str(f"touch {marker}") + b"\x85R")
    exec_ = in_dict(_global("builtins", "exec") + _short_str(f"open({marker!r}, 'w').close()") + b"\x85R")
    bomb = [b"x"]
    for _ in range(60):
        bomb = [bomb, bomb]
    depth = C.DEEP_PICKLE_LEVELS
    deep = in_dict(b"]" * depth + b"a" * (depth - 1))
    valid = pickle.dumps({"fuzz": list(range(50))}, 2)
    huge_raw = pickle.dumps({"fuzz": "x" * (C.HUGE_PICKLE_CHARS * 3 // 4)}, 2)
    return [
        ("pickle: calls os.system (would run code)", _b64(system)),
        ("pickle: calls builtins.exec (would run code)", _b64(exec_)),
        (f"pickle: {C.HUGE_PICKLE_CHARS} chars of base64", _b64(huge_raw)),
        ("pickle: reference bomb (2^60 values in a few hundred bytes)", _b64(pickle.dumps({"fuzz": bomb}, 2))),
        (f"pickle: {depth} nested lists", _b64(deep)),
        ("pickle: valid pickle truncated by half", _b64(valid[: len(valid) // 2])),
        ("pickle: not base64", "!!not base64 at all!!"),
    ]


def pickle_cases(cls: type, path: str, marker: str) -> list[FuzzCase]:
    """Init commands (``SmachContainerInitialStatusCmd``) addressed to container ``path`` (a real one,
    so that the server gets past its path check) with no initial state and a crafted ``local_data``."""
    out = []
    for label, text in crafted_pickles(marker):
        msg = cls(path=path, initial_states=[], local_data=text)
        out.append(FuzzCase(f"{label} (to {path})", serialize(msg)))
    return out
