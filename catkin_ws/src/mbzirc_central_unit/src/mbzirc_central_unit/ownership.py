"""Floor ownership: one water UAV per facade floor and per indoor floor, released when its owner fails,
goes silent or crashes, and rebuilt from what the agents are doing after a restart."""
from __future__ import annotations

from typing import Optional

from . import constants as C
from . import geometry as G
from .bookkeeping import Bookkeeping
from .command import Command, StrategyParams
from .transit import near_building
from .world_model import WorldView


class FloorOwnership:
    def __init__(self, params: StrategyParams, book: Bookkeeping) -> None:
        self.p = params
        self.book = book
        self.floor_owner: dict[int, str] = {}
        self.indoor_owner: dict[int, str] = {}

    def take(self, kind: str, floor: int, agent_id: str) -> None:
        """agent_id owns that floor (facade or indoor) now, and nothing else."""
        self.release(agent_id)
        (self.floor_owner if kind == C.KIND_FACADE else self.indoor_owner)[floor] = agent_id

    def release(self, agent_id: str) -> None:
        """Free the floors (facade and indoor) an agent owns."""
        for d in (self.floor_owner, self.indoor_owner):
            for k in [k for k, v in d.items() if v == agent_id]:
                del d[k]

    def give_up(self, cmd: Command) -> None:
        """The agent failed `cmd` too often: free the floor it worked on so that another agent takes it."""
        if cmd.task in C.FACADE_TASKS and self.floor_owner.get(_floor_of_target(cmd)) == cmd.agent_id:
            self.floor_owner.pop(_floor_of_target(cmd), None)
        floor = cmd.target[0] if isinstance(cmd.target, tuple) else None
        if cmd.task in (C.ENTER_BUILDING, C.SEARCH_INDOOR) and self.indoor_owner.get(floor) == cmd.agent_id:
            self.indoor_owner.pop(floor, None)

    def owner_alive(self, owner: Optional[str], world: WorldView) -> bool:
        a = world.agents.get(owner) if owner is not None else None
        return a is not None and a.alive(world.now, self.p.agent_timeout) and not self.book.broken(owner)

    def free_for(self, floor: int, agent_id: str, world: WorldView) -> bool:
        """True if no other alive UAV works at that floor, outside or inside: one UAV per floor altitude
        keeps a facade search and a window entry of the same floor from meeting."""
        for owners in (self.floor_owner, self.indoor_owner):
            owner = owners.get(floor)
            if owner is not None and owner != agent_id and self.owner_alive(owner, world):
                return False
        # A UAV that gave the floor up may still be there (leaving through a window, on its way to an
        # elevator): the floor stays taken until it is away, or the two meet at the window and wait for
        # each other's reserved regions forever (seen in a mission).
        return not any(o.agent_id != agent_id and o.is_uav and o.alive(world.now, self.p.agent_timeout)
                       and not o.landed and G.floor_of(o.z) == floor and near_building(o)
                       for o in world.agents.values())

    def rebuild(self, world: WorldView) -> None:
        """After a restart nothing is owned: agents busy on a facade or indoors keep the floor they are on."""
        for a in world.agents.values():
            if not a.is_uav or not a.alive(world.now, self.p.agent_timeout) or a.payload != C.PAYLOAD_WATER:
                continue
            f = G.floor_of(a.z)
            if a.active_task in C.FACADE_TASKS and f not in self.floor_owner:
                self.floor_owner[f] = a.agent_id
            if a.active_task in (C.ENTER_BUILDING, C.SEARCH_INDOOR, C.EXTINGUISH_INDOOR_FIRE) \
                    and f not in self.indoor_owner:
                self.indoor_owner[f] = a.agent_id
        for d in (self.floor_owner, self.indoor_owner):
            for f in [f for f, o in d.items() if not self.owner_alive(o, world)]:
                del d[f]


def _floor_of_target(cmd: Command) -> Optional[int]:
    return cmd.goal.get("_floor", cmd.target if cmd.task == C.SEARCH_FACADE else None)
