"""The Challenge 3 strategy: which task each idle agent runs next (pure logic, no ROS).

The central unit node calls `Strategy.decide(world)` at every tick with a `WorldView` rebuilt from the
agents' data_feeds and /estimated_objects, sends the returned `Command`s as action goals, and reports
each outcome with `Strategy.on_result`. The strategy follows docs/architecture.md ("Central unit"):

1. the UGV searches the ground floor indoors through the door and puts out what it finds;
2. the blanket UAV visits the outdoor fire holders, covers a fire, gets a new blanket at home, repeats;
3. water UAVs own one facade floor each (priority `floor_priority`, the first floor last), search it,
   put out its fire until the tank is empty, refill, and take the next unassigned floor;
4. floors of failed or silent agents are released and taken by others;
5. each UAV flies at its own altitude and changes altitude only inside its virtual elevator;
6. with no facade floor left, a second facade search, and then the indoor floors through windows.

The parts, along the strategy's seams: `bookkeeping` (goals in flight, searches, failures, crashes),
`ownership` (one water UAV per floor), one decider per role (`ugv_decider`, `blanket_decider`,
`water_decider` with its `indoor_phase`) and `transit` (routes, elevators, the way out and home). This
class makes one of each, runs the deciders for the idle agents and passes the node's reports on.

.. note:: The memory kept here (searches done, failures, last finished task) only saves time: a restarted
   strategy starts empty, re-derives floor ownership from what the agents are doing, and at worst
   repeats a search. Nothing the mission needs lives only in this object.
"""
from __future__ import annotations

from typing import Any, Optional

from . import constants as C

from .blanket_decider import BlanketDecider
from .bookkeeping import Bookkeeping
from .command import Command, StrategyParams
from .indoor_phase import IndoorPhase
from .ownership import FloorOwnership
from .transit import Router
from .ugv_decider import UgvDecider
from .water_decider import WaterDecider
from .world_model import WorldView

__all__ = ["Command", "Strategy", "StrategyParams"]


class Strategy:
    """Decides the next task of every idle agent; see the module docstring."""

    def __init__(self, params: Optional[StrategyParams] = None) -> None:
        self.p = params or StrategyParams()
        self.book = Bookkeeping(self.p)
        self.owners = FloorOwnership(self.p, self.book)
        self.router = Router(self.p, self.book)
        parts = (self.p, self.book, self.owners, self.router)
        self.ugv = UgvDecider(*parts)
        self.blanket = BlanketDecider(*parts)
        self.indoor = IndoorPhase(*parts)
        self.water = WaterDecider(*parts, indoor=self.indoor)
        self._now = 0.0  # sim time of the last decision

    # ---- what the node (status, recorder) and the tests read ---------------------------------------
    @property
    def floor_owner(self) -> dict[int, str]:
        return self.owners.floor_owner

    @property
    def indoor_owner(self) -> dict[int, str]:
        return self.owners.indoor_owner

    @property
    def in_flight(self) -> dict[str, Command]:
        return self.book.in_flight

    @property
    def crashed(self) -> set[str]:
        return self.book.crashed

    @property
    def facade_searches(self) -> Any:
        return self.book.facade_searches

    def altitude(self, agent_id: str) -> float:
        """Transit altitude of a UAV (see transit.Router.altitude)."""
        return self.router.altitude(agent_id)

    def probably_out(self, fire_id: int) -> bool:
        """A fire repeatedly not seen hot after water from its watering pose (failure_rules.py), for the status."""
        return self.book.unconfirmed.probably_out(fire_id)

    def broken(self, agent_id: str) -> bool:
        """An agent that gets no more work (see bookkeeping.Bookkeeping.broken)."""
        return self.book.broken(agent_id)

    # ---- reports of the node -----------------------------------------------------------------------
    def on_sent(self, cmd: Command) -> None:
        """The node sent `cmd`: the agent is busy with it until `on_result`."""
        self.book.on_sent(cmd)

    def on_result(self, cmd: Command, succeeded: bool, result: Optional[dict[str, Any]] = None,
                  now: Optional[float] = None) -> None:
        """Outcome of a command at sim time `now` (default: the last decision's): updates search counts,
        failures, and releases work given up."""
        gave_up = self.book.record(cmd, succeeded, result, self._now if now is None else now)
        if succeeded:
            return
        if self.book.broken(cmd.agent_id):
            self.owners.release(cmd.agent_id)  # e.g. crashed: whatever it owned goes to the others
        if gave_up:
            self.owners.give_up(cmd)

    def take_notes(self) -> list[str]:
        """Log lines of the failure rules (failure_rules.py) since the last call, for the node to log."""
        return self.book.take_notes()

    def forget(self, cmd: Command) -> None:
        """A command that could not be sent (no action server yet): not in flight, not a failure."""
        self.book.forget(cmd)

    def on_silent(self, agent_id: str) -> None:
        """An agent's data_feed stopped: forget its goal and release everything it owned."""
        self.book.forget_agent(agent_id)
        self.owners.release(agent_id)

    def release(self, agent_id: str) -> None:
        """Free the floors (facade and indoor) an agent owns."""
        self.owners.release(agent_id)

    # ---- decisions ---------------------------------------------------------------------------------
    def decide(self, world: WorldView) -> list[Command]:
        """Commands for every alive, idle agent without a goal in flight. Each returned command counts as
        in flight; the caller calls `on_result` when it ends, or `on_result(cmd, False)` / `forget` if it
        could not be sent."""
        self._now = world.now
        for agent_id in self.book.note_crashes(world):
            self.owners.release(agent_id)
        self.owners.rebuild(world)
        out: list[Command] = []
        for agent_id in sorted(world.agents):
            a = world.agents[agent_id]
            if not a.alive(world.now, self.p.agent_timeout) or agent_id in self.book.in_flight or not a.is_idle:
                continue
            self.book.note_way_in(agent_id, a.position[:2])
            if self.book.waiting_for_reported_fires(agent_id, world) or self.book.broken(agent_id):
                continue
            if self.book.not_ready(a):
                continue
            if not a.is_uav:
                cmd = self.ugv.decide(a, world)
            elif a.payload == C.PAYLOAD_BLANKET:
                cmd = self.blanket.decide(a, world)
            else:
                cmd = self.water.decide(a, world)
            if cmd is not None and self.book.backing_off(cmd, world.now):
                continue  # the same leg was just seen blocked: wait (failure_rules.py)
            if cmd is not None:
                self.book.on_sent(cmd)  # in flight at once: later decisions of this tick see it
                out.append(cmd)
        return out

    def work_left(self, world: WorldView) -> bool:
        """True while some fire may still be found or put out by the robots alive."""
        floors_left = self.water.facade_floors_open(world) or self.indoor.floors_open(world)
        return bool(floors_left or self.blanket.work_left(world) or self.ugv.work_left(world))
