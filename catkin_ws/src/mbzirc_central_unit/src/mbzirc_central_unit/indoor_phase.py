"""The water UAVs' indoor phase: which indoor floors and rooms are left, and the next step towards a
floor's rooms (to the window, in through it, search, put the fire out, out through the same window)."""
from __future__ import annotations

import math
from typing import Optional

from . import constants as C
from . import geometry as G
from .command import Command
from .decider import Decider
from .layout import Room
from .transit import at, inside_tower
from .ugv_decider import DOOR
from .world_model import AgentView, FireView, WorldView

# m: an agent this close to an indoor holder's viewpoint, horizontally (its reported height is off the flown one
# by the vertical GNSS error, transit.exit_path), puts the fire out from there
VIEWPOINT_TOL = 0.7
VIEWPOINT_MAX_DIST = 3.0  # m between a fire track and the viewpoint (2 m in front of its holder) used for it


class IndoorPhase(Decider):
    def rooms_to_search(self, floor: int) -> list[int]:
        """Rooms of a floor searched fewer times than the limit, least searched first."""
        searches = self.book.indoor_searches
        rooms = range(len(self.p.layout.rooms.get(floor, [])))
        left = [i for i in rooms if searches[(floor, i)] < self.p.facade_searches]
        return sorted(left, key=lambda i: (searches[(floor, i)], i))

    def room_ok(self, a: AgentView, floor: int, idx: int) -> bool:
        """False once this agent failed to search the room, or to enter it, too often (a window the laser
        finds too narrow, e.g. an interior wall's end behind it: explored layouts know no interior wall)."""
        target = (floor, idx)
        return self.book.ok(a, C.SEARCH_INDOOR, target) and self.book.window_ok(a, target)

    def uav_floors(self, world: WorldView) -> list[int]:
        """Indoor floors for the UAVs: floors 1-2, and the ground floor too once the UGV is gone or gave up."""
        floors = list(self.p.indoor_floors)
        ugvs = [a for a in world.agents.values() if not a.is_uav]
        ugv_alive = any(a.alive(world.now, self.p.agent_timeout) for a in ugvs)
        ugv_done = self.book.indoor_searches[DOOR] >= self.p.facade_searches or any(
            n >= self.p.max_failures for (aid, task, tgt), n in self.book.failures.items()
            if task in (C.SEARCH_INDOOR, C.EXTINGUISH_INDOOR_FIRE) and aid in {u.agent_id for u in ugvs})
        if self.p.uavs_take_ground_floor_indoors and 0 not in floors and (not ugv_alive or ugv_done):
            floors.append(0)
        return floors

    def floors_open(self, world: WorldView) -> list[int]:
        return [f for f in self.uav_floors(world)
                if not world.extinguished_on(C.KIND_INDOOR, f)
                and (world.fires_of(C.KIND_INDOOR, f) or self.rooms_to_search(f))]

    def step(self, a: AgentView, floor: int, fire: Optional[FireView]) -> Optional[Command]:
        """Next task towards a floor's rooms: to the window, in through it, search, put the fire out."""
        layout = self.p.layout
        rooms = layout.rooms.get(floor, [])
        inside = inside_tower(a) and G.floor_of(a.z) == floor
        if fire is not None:
            # the fire's side of its wall is its viewpoint's (2 m in front of the holder): an estimate on
            # the wall's line, a few centimetres off, may fall on the other side (realistic seed 103: two
            # UAVs sent from the east room to the west viewpoint, through the interior wall)
            view = self._viewpoint_of(floor, fire)
            there = view[:3] if view is not None else fire.position
            if inside and layout.clear_indoors(floor, a.position, there):
                if view is not None and math.dist(a.position[:2], view[:2]) > VIEWPOINT_TOL \
                        and self.book.ok(a, C.SEARCH_INDOOR, ("view", fire.fire_id)):
                    # water along the wall's normal: from anywhere else the jet meets the wall at a slant
                    # and the estimate's error sends most of it beside the container
                    return Command(a.agent_id, C.SEARCH_INDOOR, {"floor": floor, "path": [view]},
                                   f"to the viewpoint of indoor fire {fire.fire_id}, floor {floor}",
                                   ("view", fire.fire_id))
                return Command(a.agent_id, C.EXTINGUISH_INDOOR_FIRE, {"fire_id": fire.fire_id, "_floor": floor},
                               f"water on indoor fire {fire.fire_id}, floor {floor}", fire.fire_id)
            idx = self.room_to_reach(floor, fire, a)
            if idx is None:
                return None
            last = self.book.last_done.get(a.agent_id)
            if inside and last is not None and last.task == C.ENTER_BUILDING and last.target == (floor, idx):
                # just in through the window that reaches it, with no clear line to its viewpoint: water it
                # from this room (the task faces the fire, stops at the wall its laser sees and looks for it),
                # never out through the same window to come in again (realistic seed 101: an estimate 1.4 m
                # through the wall from its holder; UAV 3 went in and out of floor 2 for 600 s, the fire
                # left at 58 %)
                if not self.book.ok(a, C.EXTINGUISH_INDOOR_FIRE, fire.fire_id):
                    return None
                return Command(a.agent_id, C.EXTINGUISH_INDOOR_FIRE, {"fire_id": fire.fire_id, "_floor": floor},
                               f"water on indoor fire {fire.fire_id}, floor {floor}, from room {idx}",
                               fire.fire_id)
            return self._to_room(a, floor, idx, rooms[idx], inside, f"to indoor fire {fire.fire_id}")
        left = [i for i in self.rooms_to_search(floor) if self.room_ok(a, floor, i)]
        if not left:
            return None
        idx = left[0]
        room = rooms[idx]
        last = self.book.last_done.get(a.agent_id)
        just_entered = last is not None and last.task == C.ENTER_BUILDING and last.target == (floor, idx)
        if just_entered or inside and math.dist(a.position[:2], room.inner[:2]) < 2.5:
            return Command(a.agent_id, C.SEARCH_INDOOR, {"floor": floor, "path": list(room.path)},
                           f"searching floor {floor} indoors (room {idx})", (floor, idx))
        return self._to_room(a, floor, idx, room, inside, f"to search room {idx}")

    def room_to_reach(self, floor: int, fire: FireView, a: Optional[AgentView] = None) -> Optional[int]:
        """The room to reach an indoor fire through (None: no room reaches it, not a target); with an agent,
        none whose window that agent failed to enter too often.

        Rule: the room whose search found the fire, when known and its viewpoint is reachable from there: it
        was seen from there. Else the room of its viewpoint (the holder's side of its wall), else the rooms
        that see the estimate, nearest first. Never the estimate alone first: on a wall's line, a GNSS error of
        a few decimetres puts it on the other side or inside the wall, where no room sees it (explored
        layouts: the nearest window may open on the wall's other side). A fire seen from one room through a
        doorway but watered from the next one is reached through the next one: entered through the finding
        room, a UAV found no clear way to the viewpoint, was sent out through the same window to reach that
        room, and in again, 6 times in 300 s (realistic seed 109: floor 1 never searched). A window the
        agent's laser found too narrow (an interior wall's end behind it, unknown to an explored layout)
        gives way to the next room that sees the fire (explore + GNSS-denied seed 101: UAV 2 sent to floor
        1's facade-B window 10 times in 250 s, none passable, its fire never watered)."""
        view = self._viewpoint_of(floor, fire)
        there = view[:3] if view is not None else fire.position
        rooms = self.p.layout.rooms.get(floor, [])
        candidates = []
        found = self.book.fire_rooms.get(fire.fire_id)
        if found is not None and found[0] == floor:
            if view is None or (found[1] < len(rooms)
                                and self.p.layout.clear_indoors(floor, rooms[found[1]].inner, there)):
                candidates.append(found[1])
        candidates += self.p.layout.rooms_seeing(floor, there)
        usable = [i for i in candidates if a is None or self.book.window_ok(a, (floor, i))]
        return usable[0] if usable else None

    def _viewpoint_of(self, floor: int, fire: FireView) -> Optional[tuple]:
        """The layout's viewpoint (facing the holder along its normal) of the holder nearest the fire; None
        when the rooms are the windows' (explored: no holder known, the agent faces the fire from its side)."""
        if self.p.layout.explored:
            return None
        views = [v for r in self.p.layout.rooms.get(floor, []) for v in r.path]
        near = [v for v in views if math.dist(v[:3], fire.position) <= VIEWPOINT_MAX_DIST]
        return min(near, key=lambda v: math.dist(v[:3], fire.position)) if near else None

    def _to_room(self, a: AgentView, floor: int, idx: int, room: Room, inside: bool, why: str) -> Command:
        """enter_building when in front of the room's window, else a transit there (leaving first)."""
        if not inside and at(a, room.entry):
            return Command(a.agent_id, C.ENTER_BUILDING, {"floor": floor, "entry": room.entry},
                           f"entering floor {floor} through the window ({why})", (floor, idx))
        return self.router.transit(a, room.entry, f"to the window of floor {floor} ({why})", floor)
