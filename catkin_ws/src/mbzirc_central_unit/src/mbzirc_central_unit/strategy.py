"""The Challenge 3 strategy: which task each idle agent runs next (pure logic, no ROS).

The central unit node calls `Strategy.decide(world)` at every tick with a `WorldView` rebuilt from the
agents' data_feeds and /estimated_objects, sends the returned `Command`s as action goals, and reports
each outcome with `Strategy.on_result`. The strategy follows architecture.md ("Central unit"):

1. the UGV searches the ground floor indoors through the door and puts out what it finds;
2. the blanket UAV visits the outdoor fire holders, covers a fire, gets a new blanket at home, repeats;
3. water UAVs own one facade floor each (priority `floor_priority`, the first floor last), search it,
   put out its fire until the tank is empty, refill, and take the next unassigned floor;
4. floors of failed or silent agents are released and taken by others;
5. each UAV flies at its own altitude and changes altitude only inside its virtual elevator;
6. with no facade floor left, a second facade search, and then the indoor floors through windows.

.. note:: The memory kept here (searches done, failures, last finished task) only saves time: a restarted
   strategy starts empty, re-derives floor ownership from what the agents are doing, and at worst
   repeats a search. Nothing the mission needs lives only in this object.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Optional, Sequence

from . import constants as C
from . import geometry as G
from .layout import Layout, Room
from .world_model import AgentView, FireView, WorldView


# The blanket UAV's searches in turn: the known outdoor holders (quick), then a sweep of the open area.
GROUND_SEARCH_PLAN = ("holders", "holders", "sweep", "holders", "sweep")
MIN_TRANSIT_Z = 1.5  # m: a transit starting lower climbs straight up to this first
PLAUSIBLE_RADIUS = 2.0  # m from a holder of the layout for a facade / indoor fire track to be a target
VIEWPOINT_TOL = 0.7  # m: an agent this close to an indoor holder's viewpoint puts the fire out from there
VIEWPOINT_MAX_DIST = 3.0  # m between a fire track and the viewpoint (2 m in front of its holder) used for it
PENDING_TICKS = 10  # decision ticks an agent waits for the fires its search reported
ELEVATOR_BUSY_COST = 40.0  # m added to a route through an elevator another UAV is transiting


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
    # UAVs search the ground floor indoors when the UGV is gone (the agents accept floors 1-2 only now).
    uavs_take_ground_floor_indoors: bool = False


class Strategy:
    """Decides the next task of every idle agent; see the module docstring."""

    def __init__(self, params: Optional[StrategyParams] = None) -> None:
        self.p = params or StrategyParams()
        self.floor_owner: dict[int, str] = {}
        self.indoor_owner: dict[int, str] = {}
        self.facade_searches: Counter[int] = Counter()
        self.indoor_searches: Counter[tuple[int, Any]] = Counter()  # (floor, room index or "door")
        self.ground_searches = 0
        self.failures: Counter[tuple[str, str, Any]] = Counter()
        self.in_flight: dict[str, Command] = {}
        self.last_done: dict[str, Command] = {}
        self.finished: set[str] = set()  # agents sent home for good
        # Fire ids a search just reported, not yet in /estimated_objects: the agent waits a few ticks.
        self.pending_ids: dict[str, tuple[set[int], int]] = {}
        self.consecutive_failures: Counter[str] = Counter()
        self.seen_flying: set[str] = set()
        self.seen_ready: set[str] = set()   # agents whose UAL reported a state (not UNINITIALIZED) once
        self.crashed: set[str] = set()  # robots seen moving, now UNINITIALIZED: the simulator's crash state

    # ---- bookkeeping -----------------------------------------------------------------------------
    def altitude(self, agent_id: str) -> float:
        """Transit altitude of a UAV: its own, so that no two UAVs share one outside the building."""
        if agent_id in self.p.altitudes:
            return float(self.p.altitudes[agent_id])
        try:
            k = int(agent_id)
        except ValueError:
            k = 1
        return C.ALTITUDE_BASE + C.ALTITUDE_STEP * max(0, k - 1)

    @staticmethod
    def elevator(agent_id: str) -> int:
        """Virtual elevator of a UAV: even ids the north-west one, odd ids the south-east one."""
        try:
            return int(agent_id) % 2
        except ValueError:
            return 0

    def on_sent(self, cmd: Command) -> None:
        """The node sent `cmd`: the agent is busy with it until `on_result`."""
        self.in_flight[cmd.agent_id] = cmd

    def on_result(self, cmd: Command, succeeded: bool, result: Optional[dict[str, Any]] = None) -> None:
        """Outcome of a command: updates search counts, failures, and releases work given up."""
        result = result or {}
        self.in_flight.pop(cmd.agent_id, None)
        if succeeded:
            self.consecutive_failures[cmd.agent_id] = 0
            self.last_done[cmd.agent_id] = cmd
            if result.get("fire_ids"):
                self.pending_ids[cmd.agent_id] = ({int(i) for i in result["fire_ids"]}, PENDING_TICKS)
            if cmd.task == C.SEARCH_FACADE:
                self.facade_searches[cmd.target] += 1
            elif cmd.task == C.SEARCH_INDOOR:
                self.indoor_searches[cmd.target] += 1
            elif cmd.task == C.LOOK_FOR_GROUND_FIRES:
                self.ground_searches += 1
            return
        self.last_done.pop(cmd.agent_id, None)
        key = (cmd.agent_id, cmd.task, cmd.target)
        self.failures[key] += 1
        self.consecutive_failures[cmd.agent_id] += 1
        if self.broken(cmd.agent_id):
            self.release(cmd.agent_id)  # e.g. crashed: whatever it owned goes to the others
        if self.failures[key] >= self.p.max_failures:
            # Give that work up for this agent: free its floor so that another agent takes it.
            if cmd.task in C.FACADE_TASKS and self.floor_owner.get(self._floor_of_target(cmd)) == cmd.agent_id:
                self.floor_owner.pop(self._floor_of_target(cmd), None)
            floor = cmd.target[0] if isinstance(cmd.target, tuple) else None
            if cmd.task in (C.ENTER_BUILDING, C.SEARCH_INDOOR) and self.indoor_owner.get(floor) == cmd.agent_id:
                self.indoor_owner.pop(floor, None)
            if cmd.task == C.SEARCH_FACADE:
                self.facade_searches[cmd.target] += 1  # counts as a search so that the mission moves on
            if cmd.task == C.SEARCH_INDOOR:
                self.indoor_searches[cmd.target] += 1
            if cmd.task == C.LOOK_FOR_GROUND_FIRES:
                self.ground_searches += 1

    def broken(self, agent_id: str) -> bool:
        """An agent that cannot take off any more, or failed every task of a long row (a crashed robot
        still publishes its data_feed): it gets no more work, and owns nothing."""
        return (agent_id in self.crashed
                or self.failures[(agent_id, C.TAKE_OFF, None)] >= self.p.max_failures
                or self.consecutive_failures[agent_id] >= 2 * self.p.max_failures)

    def _note_crashes(self, world: WorldView) -> None:
        """A robot that moved (UAV flying, UGV driving: FLYING_AUTO) and is UNINITIALIZED again has crashed
        (it lies where it fell, deaf)."""
        for a in world.agents.values():
            if a.ual_state in (C.UAL_TAKING_OFF, C.UAL_FLYING_AUTO, C.UAL_FLYING_MANUAL):
                self.seen_flying.add(a.agent_id)
            elif a.ual_state == C.UAL_UNINITIALIZED and a.agent_id in self.seen_flying \
                    and a.agent_id not in self.crashed and a.alive(world.now, self.p.agent_timeout):
                self.crashed.add(a.agent_id)
                self.in_flight.pop(a.agent_id, None)
                self.release(a.agent_id)

    def forget(self, cmd: Command) -> None:
        """A command that could not be sent (no action server yet): not in flight, not a failure."""
        if self.in_flight.get(cmd.agent_id) is cmd:
            del self.in_flight[cmd.agent_id]

    def on_silent(self, agent_id: str) -> None:
        """An agent's data_feed stopped: forget its goal and release everything it owned."""
        self.in_flight.pop(agent_id, None)
        self.last_done.pop(agent_id, None)
        self.release(agent_id)

    def release(self, agent_id: str) -> None:
        """Free the floors (facade and indoor) an agent owns."""
        for d in (self.floor_owner, self.indoor_owner):
            for k in [k for k, v in d.items() if v == agent_id]:
                del d[k]

    def _floor_of_target(self, cmd: Command) -> Optional[int]:
        return cmd.goal.get("_floor", cmd.target if cmd.task == C.SEARCH_FACADE else None)

    # ---- ownership -------------------------------------------------------------------------------
    def _owner_alive(self, owner: Optional[str], world: WorldView) -> bool:
        a = world.agents.get(owner) if owner is not None else None
        return a is not None and a.alive(world.now, self.p.agent_timeout) and not self.broken(owner)

    def _free_for(self, floor: int, agent_id: str, world: WorldView) -> bool:
        """True if no other alive UAV works at that floor, outside or inside: one UAV per floor altitude
        keeps a facade search and a window entry of the same floor from meeting."""
        for owners in (self.floor_owner, self.indoor_owner):
            owner = owners.get(floor)
            if owner is not None and owner != agent_id and self._owner_alive(owner, world):
                return False
        # A UAV that gave the floor up may still be there (leaving through a window, on its way to an
        # elevator): the floor stays taken until it is away, or the two meet at the window and wait for
        # each other's reserved regions forever (seen in a mission).
        return not any(o.agent_id != agent_id and o.is_uav and o.alive(world.now, self.p.agent_timeout)
                       and not o.landed and G.floor_of(o.z) == floor and self._near_building(o)
                       for o in world.agents.values())

    def _rebuild_ownership(self, world: WorldView) -> None:
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
            for f in [f for f, o in d.items() if not self._owner_alive(o, world)]:
                del d[f]

    # ---- decisions -------------------------------------------------------------------------------
    def decide(self, world: WorldView) -> list[Command]:
        """Commands for every alive, idle agent without a goal in flight. Each returned command counts as
        in flight; the caller calls `on_result` when it ends, or `on_result(cmd, False)` / `forget` if it
        could not be sent."""
        self._note_crashes(world)
        self._rebuild_ownership(world)
        out: list[Command] = []
        for agent_id in sorted(world.agents):
            a = world.agents[agent_id]
            if not a.alive(world.now, self.p.agent_timeout) or agent_id in self.in_flight or not a.is_idle:
                continue
            if self._waiting_for_reported_fires(agent_id, world) or self.broken(agent_id):
                continue
            if a.ual_state != C.UAL_UNINITIALIZED:
                self.seen_ready.add(agent_id)
            elif agent_id not in self.seen_ready and agent_id not in self.seen_flying:
                # its autopilot (UAL) has not reported yet, e.g. the simulator is still starting: a goal
                # now fails at once, and three such failures made the UGV give up its job (seen). Only
                # until its first state: UNINITIALIZED later is the crash state, handled as before
                continue
            if not a.is_uav:
                cmd = self._decide_ugv(a, world)
            elif a.payload == C.PAYLOAD_BLANKET:
                cmd = self._decide_blanket(a, world)
            else:
                cmd = self._decide_water(a, world)
            if cmd is not None:
                self.on_sent(cmd)  # in flight at once: later decisions of this tick see it
                out.append(cmd)
        return out

    def _waiting_for_reported_fires(self, agent_id: str, world: WorldView) -> bool:
        """True while fires the agent's last search reported have not reached /estimated_objects yet."""
        ids, ticks = self.pending_ids.get(agent_id, (set(), 0))
        if not ids or ids & set(world.fires) or ticks <= 0:
            self.pending_ids.pop(agent_id, None)
            return False
        self.pending_ids[agent_id] = (ids, ticks - 1)
        return True

    def work_left(self, world: WorldView) -> bool:
        """True while some fire may still be found or put out by the robots alive."""
        kinds_left = self._facade_floors_open(world) or self._indoor_floors_open(world)
        ground = self._ground_work_left(world)
        ugv = not world.extinguished_on(C.KIND_INDOOR, 0) and self.indoor_searches[(0, "door")] < 2
        return bool(kinds_left or ground or ugv)

    # UGV ------------------------------------------------------------------------------------------
    def _decide_ugv(self, a: AgentView, world: WorldView) -> Optional[Command]:
        fires = world.fires_of(C.KIND_INDOOR, 0)
        if fires and a.water_level > 0.05:  # the UGV cannot refill: it uses every drop
            f = self._nearest(a, fires)
            if self._ok(a, C.EXTINGUISH_INDOOR_FIRE, f.fire_id):
                return Command(a.agent_id, C.EXTINGUISH_INDOOR_FIRE, {"fire_id": f.fire_id},
                               f"indoor fire {f.fire_id} on the ground floor", f.fire_id)
        target = (0, "door")
        if not world.extinguished_on(C.KIND_INDOOR, 0) and self.indoor_searches[target] < self.p.facade_searches \
                and self._ok(a, C.SEARCH_INDOOR, target):
            return Command(a.agent_id, C.SEARCH_INDOOR, {"floor": 0, "path": list(self.p.ugv_indoor_path)},
                           "ground floor through the door", target)
        return None

    # blanket UAV ----------------------------------------------------------------------------------
    def _ground_work_left(self, world: WorldView) -> bool:
        out = sum(1 for f in world.fires_of(C.KIND_GROUND, actionable=False) if f.extinguished)
        if out >= self.p.num_ground_fires:
            return False
        return bool(world.fires_of(C.KIND_GROUND)) or self.ground_searches < len(GROUND_SEARCH_PLAN)

    def _decide_blanket(self, a: AgentView, world: WorldView) -> Optional[Command]:
        left = self._ground_work_left(world)
        if not left:
            return self._go_home_for_good(a)
        if not a.has_blanket:
            if not self._ok(a, C.GO_HOME_AND_REFILL, None):
                return None  # the resets keep failing: nothing more this robot can do
            return Command(a.agent_id, C.GO_HOME_AND_REFILL, {}, "new blanket", None)
        if a.landed:
            return Command(a.agent_id, C.TAKE_OFF, {"height": self.altitude(a.agent_id)}, "to search the ground")
        fires = [f for f in world.fires_of(C.KIND_GROUND) if self._ok(a, C.EXTINGUISH_GROUND_FIRE, f.fire_id)]
        if fires:
            f = self._nearest(a, fires)
            return Command(a.agent_id, C.EXTINGUISH_GROUND_FIRE, {"fire_id": f.fire_id},
                           f"blanket on ground fire {f.fire_id}", f.fire_id)
        alt = self.altitude(a.agent_id)
        if GROUND_SEARCH_PLAN[min(self.ground_searches, len(GROUND_SEARCH_PLAN) - 1)] == "holders":
            path = G.ground_search_path(a.position, alt, self.p.layout.ground_holders)
            return Command(a.agent_id, C.LOOK_FOR_GROUND_FIRES, {"path": path}, "outdoor fire holders",
                           "holders")
        path = G.lawnmower_path(altitude=alt)
        return Command(a.agent_id, C.LOOK_FOR_GROUND_FIRES, {"path": path}, "sweep of the open area", "sweep")

    # water UAV ------------------------------------------------------------------------------------
    def _facade_floors_open(self, world: WorldView) -> list[int]:
        """Facade floors whose fire is not out yet and that still deserve a search or a fire job."""
        out = []
        for f in self.p.floor_priority:
            if world.extinguished_on(C.KIND_FACADE, f):
                continue
            if world.fires_of(C.KIND_FACADE, f) or self.facade_searches[f] < self.p.facade_searches:
                out.append(f)
        return out

    def _rooms_to_search(self, floor: int) -> list[int]:
        """Rooms of a floor searched fewer times than the limit, least searched first."""
        rooms = range(len(self.p.layout.rooms.get(floor, [])))
        left = [i for i in rooms if self.indoor_searches[(floor, i)] < self.p.facade_searches]
        return sorted(left, key=lambda i: (self.indoor_searches[(floor, i)], i))

    def _uav_indoor_floors(self, world: WorldView) -> list[int]:
        """Indoor floors for the UAVs: floors 1-2, and the ground floor too once the UGV is gone or gave up."""
        floors = list(self.p.indoor_floors)
        ugvs = [a for a in world.agents.values() if not a.is_uav]
        ugv_alive = any(a.alive(world.now, self.p.agent_timeout) for a in ugvs)
        door = (0, "door")
        ugv_done = self.indoor_searches[door] >= self.p.facade_searches or any(
            n >= self.p.max_failures for (aid, task, tgt), n in self.failures.items()
            if task in (C.SEARCH_INDOOR, C.EXTINGUISH_INDOOR_FIRE) and aid in {u.agent_id for u in ugvs})
        if self.p.uavs_take_ground_floor_indoors and 0 not in floors and (not ugv_alive or ugv_done):
            floors.append(0)
        return floors

    def _indoor_floors_open(self, world: WorldView) -> list[int]:
        return [f for f in self._uav_indoor_floors(world)
                if not world.extinguished_on(C.KIND_INDOOR, f)
                and (world.fires_of(C.KIND_INDOOR, f) or self._rooms_to_search(f))]

    def _decide_water(self, a: AgentView, world: WorldView) -> Optional[Command]:
        if a.water_level < self.p.min_water:
            self.release(a.agent_id)
            if not self._ok(a, C.GO_HOME_AND_REFILL, None):
                return None  # the refills keep failing: nothing more this robot can do
            return self._go_home(a, "refill: the tank is empty")
        job = self._water_job(a, world)
        if job is None:
            self.release(a.agent_id)
            return self._go_home_for_good(a)
        kind, floor, fire = job
        self.release(a.agent_id)
        (self.floor_owner if kind == C.KIND_FACADE else self.indoor_owner)[floor] = a.agent_id
        self.finished.discard(a.agent_id)
        if a.landed:
            return Command(a.agent_id, C.TAKE_OFF, {"height": self.altitude(a.agent_id)},
                           f"to the {kind} job on floor {floor}")
        if kind == C.KIND_FACADE:
            return self._facade_step(a, floor, fire)
        return self._indoor_step(a, floor, fire)

    def _water_job(self, a: AgentView, world: WorldView) -> Optional[tuple[str, int, Optional[FireView]]]:
        """(kind, floor, fire or None) of the next job of a water UAV, in strategy order."""
        aid = a.agent_id
        # 1. a known facade fire on my floor, then on a floor nobody alive owns (nearest first).
        mine = [f for f in world.fires_of(C.KIND_FACADE)
                if self.floor_owner.get(f.floor) == aid and self._fire_ok(a, f)]
        free = [f for f in world.fires_of(C.KIND_FACADE)
                if self._free_for(f.floor, aid, world) and self._fire_ok(a, f)]
        for group in (mine, free):
            if group:
                f = self._nearest(a, group)
                return (C.KIND_FACADE, f.floor, f)
        # 2. an indoor fire already known on a floor I own or nobody owns.
        indoor = [f for f in world.fires_of(C.KIND_INDOOR) if f.floor in self._uav_indoor_floors(world)
                  and self._free_for(f.floor, aid, world) and self._fire_ok(a, f)
                  and self.p.layout.room_for(f.floor, f.position) is not None]
        if indoor:
            f = self._nearest(a, indoor)
            return (C.KIND_INDOOR, f.floor, f)
        # 3. my floor or the next free floor, first searches before second ones.
        open_floors = self._facade_floors_open(world)
        first = [f for f in open_floors if self.facade_searches[f] == 0]
        second = [f for f in open_floors if self.facade_searches[f] >= 1]
        second = [f for f in second if self.facade_searches[f] < self.p.facade_searches]
        indoor_floors = [f for f in self._indoor_floors_open(world)
                         if any(self._ok(a, C.SEARCH_INDOOR, (f, i)) for i in self._rooms_to_search(f))]
        groups = [first, second, indoor_floors] if self.p.second_search_first else [first, indoor_floors, second]
        for group in groups:
            is_indoor = group is indoor_floors
            owner_map = self.indoor_owner if is_indoor else self.floor_owner
            kind = C.KIND_INDOOR if is_indoor else C.KIND_FACADE
            candidates = [f for f in group if self._free_for(f, aid, world)
                          and (is_indoor or self._ok(a, C.SEARCH_FACADE, f))
                          and self._ok(a, C.FOLLOW_PATH, ("transit", f))]
            if not candidates:
                continue
            owned = [f for f in candidates if owner_map.get(f) == aid]
            if owned:
                return (kind, owned[0], None)
            # A UAV already at a floor (e.g. after a restart) keeps it when it is a candidate.
            here = G.floor_of(a.z)
            if here in candidates and self._near_building(a):
                return (kind, here, None)
            return (kind, candidates[0], None)
        return None

    def _facade_step(self, a: AgentView, floor: int, fire: Optional[FireView]) -> Command:
        """Next task towards searching a floor or putting out a facade fire: elevator transit first."""
        if fire is not None:
            last = self.last_done.get(a.agent_id)
            if last is not None and last.task == C.GO_TO_FACADE_FIRE and last.target == fire.fire_id:
                return Command(a.agent_id, C.EXTINGUISH_FACADE_FIRE, {"fire_id": fire.fire_id, "_floor": floor},
                               f"water on facade fire {fire.fire_id}, floor {floor}", fire.fire_id)
            vp = G.viewpoint(fire.position, standoff=C.FACADE_STANDOFF)
            close = math.dist(a.position, fire.position) <= C.FACADE_STANDOFF + 1.5 and abs(a.z - fire.z) < 1.5
            if not close and not self._at(a, vp):
                return self._transit(a, vp, f"to facade fire {fire.fire_id}, floor {floor}", floor)
            return Command(a.agent_id, C.GO_TO_FACADE_FIRE,
                           {"fire_id": fire.fire_id, "distance": self.p.fire_distance, "_floor": floor},
                           f"facing facade fire {fire.fire_id}, floor {floor}", fire.fire_id)
        paths = [G.facade_search_path(floor, self.p.layout.facade_holders, reverse=r) for r in (False, True)]
        path = paths[0]
        ready = [p for p in paths if p and self._at(a, p[0])]
        if ready:
            path = ready[0]
        elif path:
            # Search in the direction whose first viewpoint is the quickest to reach.
            path = min(paths, key=lambda p: self._route(a, a.position, p[0])[0])
        if not path:
            self.facade_searches[floor] = max(self.facade_searches[floor], self.p.facade_searches)
            return Command(a.agent_id, C.HOVER, {"duration": 1.0}, f"floor {floor} has no fire holder")
        if not self._at(a, path[0]):
            return self._transit(a, path[0], f"to floor {floor} via the elevator", floor)
        return Command(a.agent_id, C.SEARCH_FACADE, {"floor": floor, "path": path},
                       f"searching the facades of floor {floor}", floor)

    def _indoor_step(self, a: AgentView, floor: int, fire: Optional[FireView]) -> Optional[Command]:
        """Next task towards a floor's rooms: to the window, in through it, search, put the fire out."""
        layout = self.p.layout
        rooms = layout.rooms.get(floor, [])
        inside = self._inside_tower(a) and G.floor_of(a.z) == floor
        if fire is not None:
            if inside and layout.clear_indoors(floor, a.position, fire.position):
                view = self._viewpoint_of(floor, fire)
                if view is not None and math.dist(a.position, view[:3]) > VIEWPOINT_TOL \
                        and self._ok(a, C.SEARCH_INDOOR, ("view", fire.fire_id)):
                    # water along the wall's normal: from anywhere else the jet meets the wall at a slant
                    # and the estimate's error sends most of it beside the container
                    return Command(a.agent_id, C.SEARCH_INDOOR, {"floor": floor, "path": [view]},
                                   f"to the viewpoint of indoor fire {fire.fire_id}, floor {floor}",
                                   ("view", fire.fire_id))
                return Command(a.agent_id, C.EXTINGUISH_INDOOR_FIRE, {"fire_id": fire.fire_id, "_floor": floor},
                               f"water on indoor fire {fire.fire_id}, floor {floor}", fire.fire_id)
            idx = layout.room_for(floor, fire.position)
            if idx is None:
                return None
            return self._to_room(a, floor, idx, rooms[idx], inside, f"to indoor fire {fire.fire_id}")
        left = [i for i in self._rooms_to_search(floor) if self._ok(a, C.SEARCH_INDOOR, (floor, i))]
        if not left:
            return None
        idx = left[0]
        room = rooms[idx]
        last = self.last_done.get(a.agent_id)
        just_entered = last is not None and last.task == C.ENTER_BUILDING and last.target == (floor, idx)
        if just_entered or inside and math.dist(a.position[:2], room.inner[:2]) < 2.5:
            return Command(a.agent_id, C.SEARCH_INDOOR, {"floor": floor, "path": list(room.path)},
                           f"searching floor {floor} indoors (room {idx})", (floor, idx))
        return self._to_room(a, floor, idx, room, inside, f"to search room {idx}")

    def _viewpoint_of(self, floor: int, fire: FireView) -> Optional[tuple]:
        """The layout's viewpoint (facing the holder along its normal) of the holder nearest the fire."""
        views = [v for r in self.p.layout.rooms.get(floor, []) for v in r.path]
        near = [v for v in views if math.dist(v[:3], fire.position) <= VIEWPOINT_MAX_DIST]
        return min(near, key=lambda v: math.dist(v[:3], fire.position)) if near else None

    def _to_room(self, a: AgentView, floor: int, idx: int, room: Room, inside: bool, why: str) -> Command:
        """enter_building when in front of the room's window, else a transit there (leaving first)."""
        if not inside and self._at(a, room.entry):
            return Command(a.agent_id, C.ENTER_BUILDING, {"floor": floor, "entry": room.entry},
                           f"entering floor {floor} through the window ({why})", (floor, idx))
        return self._transit(a, room.entry, f"to the window of floor {floor} ({why})", floor)

    @staticmethod
    def _inside_tower(a: AgentView) -> bool:
        r = G.obstacle_rect(a.z, 0.0, boxes=(C.TOWER_BOX,))
        return r is not None and G.inside(a.position, r)

    # ---- motion helpers ---------------------------------------------------------------------------
    def _transit(self, a: AgentView, target: Sequence[float], reason: str, floor: Optional[int]) -> Command:
        """follow_path from where the agent is to `target`, around the building and, to change altitude,
        through the virtual elevator that makes the way shortest (the other one when a UAV is already in
        transit through it)."""
        out = self._exit_path(a)
        if out:
            # Indoors the agents' go_to cannot plan; search_indoor moves in straight legs, so it takes the
            # UAV out through the window it came in by (looking around once more on the way).
            return Command(a.agent_id, C.SEARCH_INDOOR, {"floor": G.floor_of(a.z), "path": out},
                           f"leaving floor {G.floor_of(a.z)} through the window", ("exit", G.floor_of(a.z)))
        yaw = target[3] if len(target) > 3 else 0.0
        start = a.position
        climb = []
        if start[2] < MIN_TRANSIT_Z:
            # Close to the ground (e.g. after a fire at 0.75 m): straight up first, never a long leg low.
            start = (start[0], start[1], MIN_TRANSIT_Z)
            climb = [(*start, yaw)]
        _, elevator, route = self._route(a, start, target)
        path = climb + [(x, y, z, yaw) for x, y, z in route]
        return Command(a.agent_id, C.FOLLOW_PATH, {"path": path, "_elevator": elevator}, reason,
                       ("transit", floor))

    def _route(self, a: AgentView, origin: Sequence[float], target: Sequence[float]
               ) -> tuple[float, int, list[tuple[float, float, float]]]:
        """(cost, elevator, waypoints) of the best route from origin to target for agent `a`."""
        busy = {c.goal.get("_elevator") for aid, c in self.in_flight.items()
                if aid != a.agent_id and c.task == C.FOLLOW_PATH}
        best = None
        for e in (0, 1):
            route = G.plan_route(tuple(origin[:3]), tuple(target[:3]), e)
            pts = [tuple(origin[:3])] + route
            cost = sum(math.dist(p, q) for p, q in zip(pts, pts[1:])) + (ELEVATOR_BUSY_COST if e in busy else 0)
            if best is None or cost < best[0]:
                best = (cost, e, route)
        return best

    def _exit_path(self, a: AgentView) -> list[tuple[float, float, float, float]]:
        """Back out through the nearest window of the floor when the UAV is inside the tower."""
        if not self._inside_tower(a):
            return []
        rooms = self.p.layout.rooms.get(G.floor_of(a.z), [])
        if not rooms:
            return []
        room = min(rooms, key=lambda r: math.dist(r.inner, a.position))
        e = room.entry
        back = e[3] + math.pi  # face out while leaving
        # One waypoint per goal: the agents' search_indoor stops at the first waypoint where it knows a
        # fire of the floor, so a longer path could end inside. First to the point inside the window,
        # then straight out through it.
        if math.dist(a.position, room.inner) > 0.6:
            return [(*room.inner, back)]
        return [(e[0], e[1], e[2], back)]

    def _go_home(self, a: AgentView, reason: str) -> Command:
        """Leave the building (through the window, then the nearest free elevator down or up to the UAV's
        own altitude), then go home (and refill)."""
        if a.landed:
            return Command(a.agent_id, C.GO_HOME_AND_REFILL, {}, reason)
        alt = self.altitude(a.agent_id)
        bottoms = [(x, y, alt, 0.0) for x, y in G.elevator_points()]
        near = self._near_building(a) or abs(a.z - alt) > 0.75 or bool(self._exit_path(a))
        if near and not any(self._at(a, b) for b in bottoms):
            best = min(bottoms, key=lambda b: self._route(a, a.position, b)[0])
            return self._transit(a, best, f"leaving the building: {reason}", None)
        return Command(a.agent_id, C.GO_HOME_AND_REFILL, {}, reason)

    def _go_home_for_good(self, a: AgentView) -> Optional[Command]:
        """No work left: go home once and stay landed."""
        if a.landed or a.agent_id in self.finished:
            return None
        cmd = self._go_home(a, "no work left")
        if cmd.task == C.GO_HOME_AND_REFILL:
            self.finished.add(a.agent_id)
        return cmd

    @staticmethod
    def _near_building(a: AgentView, distance: float = C.ELEVATOR_MARGIN - 1.0) -> bool:
        r = G.obstacle_rect(a.z, distance)
        return r is not None and G.inside(a.position, r)

    @staticmethod
    def _at(a: AgentView, target: Sequence[float], tol: float = 1.0) -> bool:
        return math.dist(a.position, tuple(target[:3])) <= tol

    @staticmethod
    def _nearest(a: AgentView, fires: Sequence[FireView]) -> FireView:
        return min(fires, key=lambda f: (math.dist(a.position, f.position), f.fire_id))

    def _ok(self, a: AgentView, task: str, target: Any) -> bool:
        """False once this agent failed this task on this target too often."""
        return self.failures[(a.agent_id, task, target)] < self.p.max_failures

    def _plausible(self, f: FireView) -> bool:
        """A facade / indoor fire track within PLAUSIBLE_RADIUS of a holder of the layout. A track far from
        every holder is a stray or drifted estimate; sending a UAV to aim at it leads it into the wall."""
        layout = self.p.layout
        if f.kind == C.KIND_FACADE:
            holders = layout.facade_holders
        elif f.kind == C.KIND_INDOOR:
            holders = [h[:3] for h in layout.indoor_holders]
        else:
            return True
        return any(math.dist(f.position, h[:3]) <= PLAUSIBLE_RADIUS for h in holders)

    def _fire_ok(self, a: AgentView, f: FireView) -> bool:
        tasks = (C.GO_TO_FACADE_FIRE, C.EXTINGUISH_FACADE_FIRE) if f.kind == C.KIND_FACADE \
            else (C.EXTINGUISH_INDOOR_FIRE,)
        return all(self._ok(a, t, f.fire_id) for t in tasks) and self._ok(a, C.FOLLOW_PATH, ("transit", f.floor)) \
            and self._plausible(f)
