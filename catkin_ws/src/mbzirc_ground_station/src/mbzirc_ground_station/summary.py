"""Short human-readable text of ROS messages (action goals), without importing any message type.

Messages are read by duck typing (`__slots__`), so any goal type of any agent is summarised the same way and
a malformed field gives "?" instead of an exception.
"""
from __future__ import annotations

import math
from typing import Any

__all__ = ["summarise", "finite", "point_of"]

MAX_TEXT = 160


def finite(x: Any) -> float | None:
    """x as a finite float, or None (NaN, inf, not a number)."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def point_of(obj: Any) -> tuple[float, float, float] | None:
    """(x, y, z) of a Point, Pose or PoseStamped, or None when it has none or it is not finite."""
    for attr in ("pose", "position"):
        while hasattr(obj, attr):
            obj = getattr(obj, attr)
    xyz = tuple(finite(getattr(obj, a, None)) for a in "xyz")
    return None if None in xyz else xyz  # type: ignore[return-value]


def _one(value: Any, depth: int) -> str:
    if isinstance(value, (bool, int, str)):
        return repr(value) if isinstance(value, str) else str(value)
    if isinstance(value, float):
        return "%.2f" % value if math.isfinite(value) else "?"
    if isinstance(value, (list, tuple)):
        if value and point_of(value[0]) is not None:
            return "%d poses" % len(value)
        return "[%s]" % ", ".join(_one(v, depth + 1) for v in value[:4]) + ("..." if len(value) > 4 else "")
    p = point_of(value)
    if p is not None:
        return "(%.1f, %.1f, %.1f)" % p
    if depth < 2 and hasattr(value, "__slots__"):
        return "{%s}" % summarise(value, depth + 1)
    return "?"


def summarise(msg: Any, depth: int = 0) -> str:
    """'field=value, ...' of a message's slots (headers skipped), at most MAX_TEXT characters."""
    parts = []
    for slot in getattr(msg, "__slots__", ()):
        if slot == "header":
            continue
        try:
            parts.append("%s=%s" % (slot, _one(getattr(msg, slot), depth)))
        except Exception:  # noqa: BLE001 - a malformed field must not break the page
            parts.append("%s=?" % slot)
    text = ", ".join(parts)
    return text if len(text) <= MAX_TEXT else text[:MAX_TEXT - 3] + "..."
