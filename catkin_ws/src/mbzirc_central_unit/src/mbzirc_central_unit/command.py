"""Command and StrategyParams: what the strategy hands the node (one task for one agent), and its knobs."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

from . import constants as C
from .layout import Layout


@dataclass
class Command:
    """One task for one agent. `goal` holds the action goal fields; poses are (x, y, z, yaw) tuples."""
    agent_id: str
    task: str
    goal: dict[str, Any] = field(default_factory=dict)
    reason: str = ""
    target: Any = None  # floor, fire id or None: what the command works on

    def describe(self) -> str:
        return f"{self.task}" + (f" ({self.reason})" if self.reason else "")


@dataclass
class StrategyParams:
    """Tunable knobs (each one a ~param of the central unit node)."""
    agent_timeout: float = C.AGENT_TIMEOUT
    floor_priority: Sequence[int] = C.FLOOR_PRIORITY
    indoor_floors: Sequence[int] = C.INDOOR_FLOORS
    altitudes: dict[str, float] = field(default_factory=lambda: dict(C.DEFAULT_ALTITUDES))
    layout: Layout = field(default_factory=Layout)
    ugv_indoor_path: list[tuple[float, float, float, float]] = field(default_factory=list)
    fire_distance: float = C.FIRE_DISTANCE
    min_water: float = C.MIN_WATER
    num_ground_fires: int = 2
    facade_searches: int = 2          # searches of a floor whose fire was not found (the second search)
    second_search_first: bool = True  # the second facade search before the indoor floors
    max_failures: int = C.MAX_TASK_FAILURES
    leg_blocked_backoff: float = C.LEG_BLOCKED_BACKOFF         # failure_rules.py
    leg_blocked_backoff_max: float = C.LEG_BLOCKED_BACKOFF_MAX
    max_blocked_legs: int = C.MAX_BLOCKED_LEGS
    not_seen_hot_limit: int = C.NOT_SEEN_HOT_LIMIT
    facade_top_up_limit: int = C.FACADE_TOP_UP_LIMIT
    # UAVs search the ground floor indoors when the UGV is gone (the agents accept floors 1-2 only now).
    uavs_take_ground_floor_indoors: bool = False
