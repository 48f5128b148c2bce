"""Yaw helpers: every pose the robots exchange is flat (roll and pitch are the UAL's business)."""
from __future__ import annotations

import math
from typing import Optional


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> Optional[float]:
    """Yaw of a quaternion; None for the all-zero quaternion (a goal's way of saying "keep the current yaw")."""
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n < 1e-9:
        return None
    x, y, z, w = x / n, y / n, z / n, w / n
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quaternion_from_yaw(yaw: float) -> tuple:
    """(x, y, z, w) of a rotation of yaw about z."""
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def wrap_angle(a: float) -> float:
    """a wrapped to (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))
