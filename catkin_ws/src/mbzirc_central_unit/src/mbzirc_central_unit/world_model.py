"""What the central unit knows, rebuilt at every tick from the agents' data_feeds and /estimated_objects.

Nothing here is only in memory: a restarted central unit rebuilds the same views from the next messages.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Optional

from mbzirc_arena.c3 import classify_fire as arena_classify_fire
from mbzirc_arena.c3 import floor_of

from . import constants as C


@dataclass
class AgentView:
    """One agent as its last data_feed describes it.

    Args:
        agent_id: "0" for the UGV, "1".. for the UAVs.
        last_seen: time (s) of the last data_feed; the agent is silent when older than the timeout.
    """
    agent_id: str
    robot_type: str = C.ROBOT_UAV
    payload: str = C.PAYLOAD_WATER
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    ual_state: int = C.UAL_UNINITIALIZED
    active_task: str = ""
    active_sub_state: str = ""
    is_idle: bool = True
    battery: float = 1.0
    water_level: float = 0.0
    has_blanket: bool = False
    last_seen: float = -math.inf
    # the data_feed has carried a pose once: at start-up an agent publishes before its UAL's first pose
    # (mbzirc_arena.messages.feed_position; the central unit's AgentView starts False)
    reported: bool = True

    @property
    def position(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.z)

    @property
    def is_uav(self) -> bool:
        return self.robot_type != C.ROBOT_UGV

    @property
    def landed(self) -> bool:
        return self.ual_state in C.UAL_LANDED or (self.ual_state == C.UAL_LANDING)

    def alive(self, now: float, timeout: float) -> bool:
        """True while data_feeds keep coming (the data_feed is the agent's heartbeat)."""
        return now - self.last_seen <= timeout


@dataclass
class FireView:
    """A fire track of the object estimator, with its kind and floor worked out."""
    fire_id: int
    x: float
    y: float
    z: float
    kind: str
    status: int = C.STATUS_ACTIVE
    holder_floor: Optional[int] = None   # a facade fire's storey, from its known holder (`facade_floor`)

    @property
    def floor(self) -> int:
        return self.holder_floor if self.holder_floor is not None else floor_of(self.z)

    @property
    def position(self) -> tuple[float, float, float]:
        return (self.x, self.y, self.z)

    @property
    def extinguished(self) -> bool:
        return self.status == C.STATUS_EXTINGUISHED

    @property
    def actionable(self) -> bool:
        """A fire worth sending a robot to: not out. LOST counts (an indoor fire is lost as soon as the
        robot looks away); INACTIVE does not."""
        return self.status in (C.STATUS_ACTIVE, C.STATUS_DETECTED, C.STATUS_LOST)


KIND_OF_SUBTYPE = {C.SUBTYPE_FACADE: C.KIND_FACADE, C.SUBTYPE_GROUND: C.KIND_GROUND, C.SUBTYPE_INDOOR: C.KIND_INDOOR}


def fire_kind(sub_type: int, x: float, y: float, z: float) -> str:
    """Kind of a fire: the estimator's sub_type when it knows it, else the arena's rule on where the fire is
    (mbzirc_arena `classify_fire`, the rule the estimator applies too)."""
    if sub_type not in KIND_OF_SUBTYPE:
        sub_type = arena_classify_fire((x, y, z))
    return KIND_OF_SUBTYPE[sub_type]


def facade_floor(position: tuple[float, float, float], holders: list[tuple[float, ...]]) -> Optional[int]:
    """The storey of the known facade holder nearest a facade fire's estimate (None without holders).

    Rule: a facade fire burns in one of the holders a team knows, so its storey is that holder's, not the
    storey its estimated height falls in: the estimate carries the pose error (GNSS height off by about half
    a metre), and a holder half a metre above a storey's floor height is then read on the storey below."""
    if not holders:
        return None
    nearest_holder = min(holders, key=lambda h: math.dist(position, h[:3]))
    return floor_of(nearest_holder[2])


DUPLICATE_RADIUS = 2.0  # m


@dataclass
class WorldView:
    """Snapshot the strategy decides on."""
    now: float
    agents: dict[str, AgentView] = field(default_factory=dict)
    fires: dict[int, FireView] = field(default_factory=dict)

    def fires_of(self, kind: str, floor: Optional[int] = None, actionable: bool = True) -> list[FireView]:
        """Fires of a kind (and floor), only actionable ones by default, in id order."""
        out = [f for f in self.fires.values() if f.kind == kind and (floor is None or f.floor == floor)]
        if actionable:
            out = [f for f in out if f.actionable and not self.duplicate_of_out(f)]
        return sorted(out, key=lambda f: f.fire_id)

    def duplicate_of_out(self, fire: FireView, radius: float = DUPLICATE_RADIUS) -> bool:
        """A LOST track next to a fire already out is a stray detection of that fire (or of its decoys)."""
        return fire.status == C.STATUS_LOST and any(
            o.extinguished and o.kind == fire.kind and math.dist(o.position, fire.position) < radius
            for o in self.fires.values() if o.fire_id != fire.fire_id)

    def extinguished_on(self, kind: str, floor: Optional[int] = None) -> bool:
        """True if a fire of that kind (and floor) is known to be out."""
        return any(f.extinguished for f in self.fires_of(kind, floor, actionable=False))
