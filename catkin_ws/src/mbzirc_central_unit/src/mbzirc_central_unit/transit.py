"""Where an agent is with respect to the building, and how a UAV gets somewhere: transits around the
building at the UAV's own altitude, through the virtual elevator that makes the way shortest, out of the
building through a window, and home."""
from __future__ import annotations

import math
from typing import Optional, Sequence

from mbzirc_arena.c3 import ARENA

from . import constants as C
from . import geometry as G
from .bookkeeping import Bookkeeping
from .command import Command, StrategyParams
from .world_model import AgentView, FireView

MIN_TRANSIT_Z = 1.5  # m: a transit starting lower climbs straight up to this first
OVER_HOME = 3.0      # m (horizontal) from its own pad within which a flying UAV is sent home directly
ELEVATOR_BUSY_COST = 40.0  # m added to a route through an elevator another UAV is transiting


def near_building(a: AgentView, distance: float = C.ELEVATOR_MARGIN - 1.0) -> bool:
    r = G.obstacle_rect(a.z, distance)
    return r is not None and G.inside(a.position, r)


def inside_tower(a: AgentView) -> bool:
    r = G.obstacle_rect(a.z, 0.0, boxes=(C.TOWER_BOX,))
    return r is not None and G.inside(a.position, r)


def over_home(a: AgentView) -> bool:
    """Whether a flying UAV is within OVER_HOME (horizontal) of its own pad in the arena model, away from the
    building: its go_home_and_refill takes it from there (climb on the spot, over the pad, land), no transit
    to its altitude's elevator first. Why (realistic seed 106): a UAV left hovering 1 m over its pad by a
    failed landing was sent 'leaving the building' to climb at an elevator 12 m up; that go-to and a
    neighbour's way home waited for each other's regions for the rest of the trial."""
    homes = [h.position for h in ARENA.homes if str(h.robot_id) == str(a.agent_id)]
    return bool(homes) and not near_building(a) and math.dist(a.position[:2], homes[0][:2]) <= OVER_HOME


def at(a: AgentView, target: Sequence[float], tol: float = 1.0) -> bool:
    return math.dist(a.position, tuple(target[:3])) <= tol


def nearest(a: AgentView, fires: Sequence[FireView]) -> FireView:
    return min(fires, key=lambda f: (math.dist(a.position, f.position), f.fire_id))


class Router:
    def __init__(self, params: StrategyParams, book: Bookkeeping) -> None:
        self.p = params
        self.book = book

    def altitude(self, agent_id: str) -> float:
        """Transit altitude of a UAV: its own, so that no two UAVs share one outside the building."""
        if agent_id in self.p.altitudes:
            return float(self.p.altitudes[agent_id])
        try:
            k = int(agent_id)
        except ValueError:
            k = 1
        return C.ALTITUDE_BASE + C.ALTITUDE_STEP * max(0, k - 1)

    def transit(self, a: AgentView, target: Sequence[float], reason: str, floor: Optional[int]) -> Command:
        """follow_path from where the agent is to `target`, around the building and, to change altitude,
        through the virtual elevator that makes the way shortest (the other one when a UAV is already in
        transit through it)."""
        out = self.exit_path(a)
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
        _, elevator, route = self.route(a, start, target)
        path = climb + [(x, y, z, yaw) for x, y, z in route]
        return Command(a.agent_id, C.FOLLOW_PATH, {"path": path, "_elevator": elevator}, reason,
                       ("transit", floor))

    def route(self, a: AgentView, origin: Sequence[float], target: Sequence[float]
              ) -> tuple[float, int, list[tuple[float, float, float]]]:
        """(cost, elevator, waypoints) of the best route from origin to target for agent `a`."""
        busy = {c.goal.get("_elevator") for aid, c in self.book.in_flight.items()
                if aid != a.agent_id and c.task == C.FOLLOW_PATH}
        best = None
        for e in (0, 1):
            route = G.plan_route(tuple(origin[:3]), tuple(target[:3]), e)
            pts = [tuple(origin[:3])] + route
            cost = sum(math.dist(p, q) for p, q in zip(pts, pts[1:])) + (ELEVATOR_BUSY_COST if e in busy else 0)
            if best is None or cost < best[0]:
                best = (cost, e, route)
        return best

    def exit_path(self, a: AgentView) -> list[tuple[float, float, float, float]]:
        """Back out through the nearest window of the floor when the UAV is inside the tower."""
        if not inside_tower(a):
            return []
        rooms = self.p.layout.rooms.get(G.floor_of(a.z), [])
        if not rooms:
            return []
        room = min(rooms, key=lambda r: math.dist(r.inner, a.position))
        start = room.exit_start
        entered = self.book.entered.get(a.agent_id)
        if self.p.layout.explored and entered is not None and entered[0] == G.floor_of(a.z) \
                and isinstance(entered[1], int) and entered[1] < len(rooms):
            room = rooms[entered[1]]    # no walls known: out through the window it came in (in its sight)
            start = room.exit_start
            way_in = self.book.way_in_end_of(a.agent_id, entered)
            if way_in is not None:
                # the way out starts where the way in ended, a place it flew to: EXIT_DEPTH inside the window
                # is unknown space (c3_floor_plan_b seed 101: in floor 1's 2.7 m deep south strip it was 0.4 m
                # from an interior wall; UAV 2, sent there, hit the wall)
                start = (*way_in, start[2])
        e = room.entry
        back = e[3] + math.pi  # face out while leaving
        # One waypoint per goal: the agents' search_indoor stops at the first waypoint where it knows a
        # fire of the floor, so a longer path could end inside. First to the point inside the window
        # where the way out starts, then straight out through it.
        # horizontally only: indoors the agents fly heights by the altimeter, so the reported (GNSS) height
        # stays off the commanded one by the vertical GNSS error, and a 3D test never saw the UAV arrive
        if math.dist(a.position[:2], start[:2]) > 0.6:
            return [(*start, back)]
        return [(e[0], e[1], e[2], back)]

    def go_home(self, a: AgentView, reason: str) -> Command:
        """Leave the building (through the window, then the nearest free elevator down or up to the UAV's
        own altitude), then go home (and refill)."""
        if a.landed or over_home(a):
            return Command(a.agent_id, C.GO_HOME_AND_REFILL, {}, reason)
        alt = self.altitude(a.agent_id)
        bottoms = [(x, y, alt, 0.0) for x, y in G.elevator_points()]
        near = near_building(a) or abs(a.z - alt) > 0.75 or bool(self.exit_path(a))
        if near and not any(at(a, b) for b in bottoms):
            best = min(bottoms, key=lambda b: self.route(a, a.position, b)[0])
            return self.transit(a, best, f"leaving the building: {reason}", None)
        return Command(a.agent_id, C.GO_HOME_AND_REFILL, {}, reason)

    def go_home_for_good(self, a: AgentView) -> Optional[Command]:
        """No work left: go home once and stay landed."""
        if a.landed or a.agent_id in self.book.finished:
            return None
        cmd = self.go_home(a, "no work left")
        if cmd.task == C.GO_HOME_AND_REFILL:
            self.book.finished.add(a.agent_id)
        return cmd
