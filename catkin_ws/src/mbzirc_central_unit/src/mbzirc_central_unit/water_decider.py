"""The water UAVs' decisions: each owns one facade floor (priority `floor_priority`, the first floor last),
searches it, puts out its fire until the tank is empty, refills, and takes the next unassigned floor; with
no facade floor left, a second facade search, and then the indoor floors through windows (indoor_phase)."""
from __future__ import annotations

import math
from typing import Optional

from mbzirc_arena.holders import known_holder

from . import constants as C
from . import geometry as G
from .command import Command
from .decider import Decider
from .indoor_phase import IndoorPhase
from .transit import at, inside_tower, near_building, nearest
from .world_model import AgentView, FireView, WorldView

PLAUSIBLE_RADIUS = 2.0  # m from a holder of the layout for a facade / indoor fire track to be a target


class WaterDecider(Decider):
    def __init__(self, *parts, indoor: IndoorPhase) -> None:
        super().__init__(*parts)
        self.indoor = indoor

    def decide(self, a: AgentView, world: WorldView) -> Optional[Command]:
        if a.water_level < self.p.min_water:
            self.owners.release(a.agent_id)
            if not self.book.ok(a, C.GO_HOME_AND_REFILL, None):
                return None  # the refills keep failing: nothing more this robot can do
            return self.router.go_home(a, "refill: the tank is empty")
        job = self._job(a, world)
        if job is None:
            self.owners.release(a.agent_id)
            return self.router.go_home_for_good(a)
        kind, floor, fire = job
        self.owners.take(kind, floor, a.agent_id)
        self.book.finished.discard(a.agent_id)
        if a.landed:
            return Command(a.agent_id, C.TAKE_OFF, {"height": self.router.altitude(a.agent_id)},
                           f"to the {kind} job on floor {floor}")
        if kind == C.KIND_FACADE:
            return self._facade_step(a, floor, fire)
        return self.indoor.step(a, floor, fire)

    def facade_floors_open(self, world: WorldView) -> list[int]:
        """Facade floors whose fire is not out yet and that still deserve a search or a fire job.

        Rule (one facade fire per storey, as `extinguished_on` assumes): a floor whose fire was found and then
        watered hot until it was not seen hot (probably out, failure_rules.py) is done like one whose fire is
        out; searching its facade again finds nothing new (realistic runs: 50-105 s per such second search,
        before the indoor floors). The fire itself is still revisited at the end (`_job`, 4.). A floor whose
        fire was never seen hot from its watering pose (misplaced) is searched once more (`book.search_again`):
        the fire may burn elsewhere on it (realistic seed 108: D_3 never searched again, 0.0)."""
        out = []
        for f in self.p.floor_priority:
            if world.extinguished_on(C.KIND_FACADE, f):
                continue
            fires = world.fires_of(C.KIND_FACADE, f)
            if self._confirmed(fires) or f in self.book.search_again:
                out.append(f)
            elif not fires and self.book.facade_searches[f] < self.p.facade_searches:
                out.append(f)
        return out

    def _job(self, a: AgentView, world: WorldView) -> Optional[tuple[str, int, Optional[FireView]]]:
        """(kind, floor, fire or None) of the next job of a water UAV, in strategy order."""
        aid = a.agent_id
        owners = self.owners
        # 0. the room just entered is searched before anything else: a room's search takes 5-20 s, out
        #    through the window and back in again later 60-100 s
        entered = self._room_just_entered(a, world)
        if entered is not None:
            return (C.KIND_INDOOR, entered, None)
        indoor = [f for f in self._confirmed(world.fires_of(C.KIND_INDOOR)) if f.floor in self.indoor.uav_floors(world)
                  and owners.free_for(f.floor, aid, world) and self._fire_ok(a, f)
                  and self.indoor.room_to_reach(f.floor, f, a) is not None]
        # 0b. a known indoor fire on the floor this UAV is inside, before any job elsewhere: it is seconds
        #     away, out through the window and back in again later 60-100 s (realistic 201: a UAV that had
        #     just found its floor's fire, full tank, left to top up a facade fire already out)
        here = [f for f in indoor if inside_tower(a) and f.floor == G.floor_of(a.z)]
        if here:
            f = nearest(a, here)
            return (C.KIND_INDOOR, f.floor, f)
        # 0c. a facade floor whose search starts where this UAV just flew to (for that search) is searched
        #     before any job elsewhere: the flight there took 30-60 s, the search takes 20-60 s and the fire it
        #     finds is watered at once, tank full (realistic seed 108: UAV 3 reached floor 2's search start
        #     twice, for the search again of a misplaced fire, and left at once for fires on floor 1 found
        #     meanwhile; floor 2's fire D_3 was never searched again, 0.0)
        reached = self._search_just_reached(a, world)
        if reached is not None:
            return (C.KIND_FACADE, reached, None)
        # 1. a known facade fire on my floor, then on a floor nobody alive owns (nearest first); fires
        #    doubted (probably out or misplaced, failure_rules.py) only when nothing else is left (4.)
        facade = self._confirmed(world.fires_of(C.KIND_FACADE))
        mine = [f for f in facade if owners.floor_owner.get(f.floor) == aid and self._fire_ok(a, f)]
        free = [f for f in facade if owners.free_for(f.floor, aid, world) and self._fire_ok(a, f)]
        for group in (mine, free):
            if group:
                f = nearest(a, group)
                return (C.KIND_FACADE, f.floor, f)
        # 2. an indoor fire already known on a floor I own or nobody owns.
        if indoor:
            f = nearest(a, indoor)
            return (C.KIND_INDOOR, f.floor, f)
        # 3. my floor or the next free floor, first searches before second ones.
        searches = self.book.facade_searches
        open_floors = self.facade_floors_open(world)
        first = [f for f in open_floors if searches[f] == 0]
        second = [f for f in open_floors if searches[f] >= 1]
        second = [f for f in second if searches[f] < self.p.facade_searches or f in self.book.search_again]
        indoor_floors = [f for f in self.indoor.floors_open(world)
                         if any(self.indoor.room_ok(a, f, i) for i in self.indoor.rooms_to_search(f))]
        groups = [first, second, indoor_floors] if self.p.second_search_first else [first, indoor_floors, second]
        for group in groups:
            is_indoor = group is indoor_floors
            owner_map = owners.indoor_owner if is_indoor else owners.floor_owner
            kind = C.KIND_INDOOR if is_indoor else C.KIND_FACADE
            candidates = [f for f in group if owners.free_for(f, aid, world)
                          and (is_indoor or self.book.ok(a, C.SEARCH_FACADE, f))
                          and self.book.ok(a, C.FOLLOW_PATH, ("transit", f))]
            if not candidates:
                continue
            owned = [f for f in candidates if owner_map.get(f) == aid]
            if owned:
                return (kind, owned[0], None)
            # A UAV already at a floor (e.g. after a restart) keeps it when it is a candidate.
            here = G.floor_of(a.z)
            if here in candidates and near_building(a):
                return (kind, here, None)
            return (kind, candidates[0], None)
        # 4. the end: fires doubted (probably out but unconfirmed, or misplaced), revisited while time remains
        late = [f for f in world.fires_of(C.KIND_FACADE) + world.fires_of(C.KIND_INDOOR)
                if self.book.unconfirmed.doubted(f.fire_id) and owners.free_for(f.floor, aid, world)
                and self._fire_ok(a, f)]
        if late:
            f = nearest(a, late)
            return (f.kind, f.floor, f)
        return None

    def _room_just_entered(self, a: AgentView, world: WorldView) -> Optional[int]:
        """The floor of the room this UAV just came into (its last task entered it) while that room is the
        next one to search there (the one IndoorPhase.step searches) and no known fire waits on that floor
        (the fire comes first: step 2); None otherwise."""
        last = self.book.last_done.get(a.agent_id)
        if last is None or last.task != C.ENTER_BUILDING or not isinstance(last.target, tuple):
            return None
        floor, idx = last.target
        left = [i for i in self.indoor.rooms_to_search(floor) if self.indoor.room_ok(a, floor, i)]
        if not left or left[0] != idx or floor not in self.indoor.floors_open(world) \
                or self._confirmed(world.fires_of(C.KIND_INDOOR, floor)) \
                or not self.owners.free_for(floor, a.agent_id, world):
            return None
        return floor

    def _search_just_reached(self, a: AgentView, world: WorldView) -> Optional[int]:
        """The facade floor this UAV's last task (a transit to that floor) took it to the start of a search
        of, while that floor is still to be searched (no known fire there to put out, a search left or one
        more owed to a misplaced fire: `book.search_again`); None otherwise."""
        last = self.book.last_done.get(a.agent_id)
        if last is None or last.task != C.FOLLOW_PATH or not isinstance(last.target, tuple) \
                or last.target[0] != "transit":
            return None
        f = last.target[1]
        searches = self.book.facade_searches[f]
        if f not in self.facade_floors_open(world) or self._confirmed(world.fires_of(C.KIND_FACADE, f)) \
                or not (searches < self.p.facade_searches or f in self.book.search_again) \
                or not self.owners.free_for(f, a.agent_id, world) or not self.book.ok(a, C.SEARCH_FACADE, f):
            return None
        paths = [G.facade_search_path(f, self.p.layout.facade_holders, reverse=r) for r in (False, True)]
        return f if any(p and at(a, p[0]) for p in paths) else None

    def _confirmed(self, fires: list[FireView]) -> list[FireView]:
        """Fires not doubted (probably out or misplaced) after repeated 'not seen hot' aborts (failure_rules.py)."""
        return [f for f in fires if not self.book.unconfirmed.doubted(f.fire_id)]

    def _facade_step(self, a: AgentView, floor: int, fire: Optional[FireView]) -> Command:
        """Next task towards searching a floor or putting out a facade fire: elevator transit first."""
        if fire is not None:
            last = self.book.last_done.get(a.agent_id)
            if last is not None and last.task == C.GO_TO_FACADE_FIRE and last.target == fire.fire_id:
                return Command(a.agent_id, C.EXTINGUISH_FACADE_FIRE, {"fire_id": fire.fire_id, "_floor": floor},
                               f"water on facade fire {fire.fire_id}, floor {floor}", fire.fire_id)
            vp = G.viewpoint(tuple(known_holder(fire.position)), standoff=C.FACADE_STANDOFF)
            close = math.dist(a.position, fire.position) <= C.FACADE_STANDOFF + 1.5 and abs(a.z - fire.z) < 1.5
            if not close and not at(a, vp):
                return self.router.transit(a, vp, f"to facade fire {fire.fire_id}, floor {floor}", floor)
            return Command(a.agent_id, C.GO_TO_FACADE_FIRE,
                           {"fire_id": fire.fire_id, "distance": self.p.fire_distance, "_floor": floor},
                           f"facing facade fire {fire.fire_id}, floor {floor}", fire.fire_id)
        paths = [G.facade_search_path(floor, self.p.layout.facade_holders, reverse=r) for r in (False, True)]
        path = paths[0]
        ready = [p for p in paths if p and at(a, p[0])]
        if ready:
            path = ready[0]
        elif path:
            # Search in the direction whose first viewpoint is the quickest to reach.
            path = min(paths, key=lambda p: self.router.route(a, a.position, p[0])[0])
        if not path:
            self.book.facade_searches[floor] = max(self.book.facade_searches[floor], self.p.facade_searches)
            return Command(a.agent_id, C.HOVER, {"duration": 1.0}, f"floor {floor} has no fire holder")
        if not at(a, path[0]):
            return self.router.transit(a, path[0], f"to floor {floor} via the elevator", floor)
        return Command(a.agent_id, C.SEARCH_FACADE, {"floor": floor, "path": path},
                       f"searching the facades of floor {floor}", floor)

    def _plausible(self, f: FireView) -> bool:
        """A facade / indoor fire track within PLAUSIBLE_RADIUS of a holder of the layout. A track far from
        every holder is a stray or drifted estimate; sending a UAV to aim at it leads it into the wall."""
        layout = self.p.layout
        if f.kind == C.KIND_FACADE:
            holders = layout.facade_holders
        elif f.kind == C.KIND_INDOOR and layout.explored:
            x0, y0, x1, y1, top = layout.arena.building("tower").footprint   # no holder known: in the tower
            x, y, z = f.position
            return x0 <= x <= x1 and y0 <= y <= y1 and z <= top
        elif f.kind == C.KIND_INDOOR:
            holders = [h[:3] for h in layout.indoor_holders]
        else:
            return True
        return any(math.dist(f.position, h[:3]) <= PLAUSIBLE_RADIUS for h in holders)

    def _fire_ok(self, a: AgentView, f: FireView) -> bool:
        tasks = (C.GO_TO_FACADE_FIRE, C.EXTINGUISH_FACADE_FIRE) if f.kind == C.KIND_FACADE \
            else (C.EXTINGUISH_INDOOR_FIRE,)
        return all(self.book.ok(a, t, f.fire_id) for t in tasks) \
            and self.book.ok(a, C.FOLLOW_PATH, ("transit", f.floor)) and self._plausible(f)
