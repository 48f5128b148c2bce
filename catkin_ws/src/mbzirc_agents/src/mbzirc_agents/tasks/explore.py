"""Exploring a floor inside (search_indoor with ~indoor_search explore): look around, go to the nearest
frontier of the sensed free space, look around again, until a fire is found, nothing is left, or the time
budget is spent; then back the way it came when no fire was found.

Why: the interior walls and the indoor fire places are not known before the trial (issue 18); the robot's
laser shows the free space and the doorways (gaps in the scan), its thermal camera the fires (found by the
fire detector and put on /estimated_objects by the estimator, as on any search). The grid and the choice of
the next viewpoint are exploration.py's; this is the task's use of them.

Rules:
- the search explores after a path whose last waypoint has no heading (a room's search, not a way out), or
  from where the leg guard stopped a leg of the path inside a building;
- the next viewpoint is a frontier of the laser's free space, or free space farther than
  ~explore_view_range from everywhere the robot looked around from (the thermal camera sees less far);
  never one gone to before, nor one within ~position_tolerance of the robot (it would not move);
- a UAV explores at the height fires are expected at (EXPECTED_FIRE_HEIGHT above the floor, from the
  public facade holders), going down to it first; its way back ends at that height;
- at every viewpoint (the search path's last waypoint first) the robot turns on the spot to the fewest
  headings whose views of ~forward_camera_fov hold every wall its laser sees within ~explore_view_range that
  no earlier look held (~explore_headings > 0: that many round the turn), looking with the thermal camera at
  each (`SearchIndoor._hot`) and adding the laser scans of the look to the floor's grid;
- viewpoints keep ~explore_view_clearance from the walls where they can, legs ~explore_clearance where
  they can and ~explore_pass_clearance at least (exploration.next_viewpoint);
- the legs to the next viewpoint are straight lines of the grid's free cells, each the sub-task `move`
  (UAV: indoor go_to, UGV: straight drive), both with the leg guard (leg_guard.py), a doorway across one
  passed guided by the laser (passage.LaserPassage.doorway) as on a planned search path, except in-sight
  (UAV) explorations, which pass no doorway: a leg the laser finds blocked holds the robot, and that viewpoint is not chosen
  again nor passed (the grid has the return that blocked it from the next look on); after MAX_BLOCKED_LEGS
  blocked legs the exploration ends;
- ~explore_in_sight (UAVs: they leave through the window they came in by a straight leg) keeps the
  viewpoints in straight sight of the first one;
- the exploration ends after ~explore_budget s; without a fire the robot goes back to the first viewpoint,
  where the caller's way out starts, along the grid's free space (the same clearances as a viewpoint's
  legs; a blocked leg: a new route from where it was held), or, with no route known, along the points it
  visited.
"""
from __future__ import annotations

import math
from typing import Optional

import statistics

import numpy as np

from mbzirc_arena.buildings import standing_at
from mbzirc_arena.c3 import ARENA

from .. import constants as C
from ..agent_task import TaskError
from ..exploration import FloorGrid, headings_to_watch, next_viewpoint, route_to, wall_bearings, watch
from ..leg_guard import LegGuard
from .uav_motion import facade_room, off_the_facades


MAX_BLOCKED_LEGS = 6     # legs found blocked before the exploration ends (the laser sees what the grid does not)
MAX_ROUTES_BACK = 3      # routes back to the start tried (each from where the last was blocked) before retracing


def expected_fire_height(arena=ARENA) -> float:
    """m above its floor a fire is looked for indoors: the median height of the public facade holders above
    their floors (1.5 m in the C3 arena). Why: the thermal camera sees +-16.5 deg; at a window's height
    (2.5 m above the floor) it sees a fire 1 m lower only from 3.4 m or more (realistic seed 104: a fire
    looked at from 1.2 m, 1 m above it, was never seen); the team expects the indoor fires where it knows
    the outdoor ones are."""
    floors = sorted(arena.floor_heights)
    return statistics.median(z - max(f for f in floors if f <= z + 1e-6) for _x, _y, z in arena.facade_holder_positions)


EXPECTED_FIRE_HEIGHT = expected_fire_height()
LOOK_OVERLAP = 3.0       # deg each look of a look-around shares with the next (a fire at the image's edge)


def look_headings(p) -> int:
    """Headings of a look-around: ~explore_headings, or (0) as many as the thermal camera's field of view
    needs to cover the whole turn. Why: 6 looks of a 33 deg camera see 198 of 360 deg (unit test: a fire
    2.5 m from a viewpoint, 29 deg off two looks, was never seen)."""
    if p.explore_headings > 0:
        return int(p.explore_headings)
    return max(1, math.ceil(360.0 / max(1.0, p.forward_camera_fov - LOOK_OVERLAP)))


def footprint_here(here) -> Optional[tuple]:
    """x_min, y_min, x_max, y_max of the (public) footprint of the building the robot stands in."""
    inside = [b for b in standing_at(here, C.BUILDINGS) if b[0] <= here[0] <= b[2] and b[1] <= here[1] <= b[3]]
    return tuple(inside[0][:4]) if inside else None


class Exploration:
    """One exploration of the floor the robot is on, run by a SearchIndoor task (`task`)."""

    def __init__(self, task, floor: int) -> None:
        self.task, self.agent, self.floor = task, task.agent, floor
        self.scans: LegGuard = task.scans     # the task's laser scans (leg_guard.LegGuard.points)
        here = self.agent.position()
        bounds = footprint_here(here)
        if bounds is None:
            raise TaskError(f'exploring floor {floor}: ({here[0]:.1f}, {here[1]:.1f}) is in no building')
        self.grid = FloorGrid(bounds, self.agent.p.explore_resolution)
        uav = self.agent.ROBOT_TYPE == 'uav'
        # a UAV keeps its facade room from the outline (uav_motion.facade_room): at the looking height its
        # laser's plane may look out through a window and never see the wall under the sill
        self.outline_room = facade_room(self.agent.p) if uav else 0.0
        # where it explores from: off the facades (a UAV), at the (true) height it came in at
        self.start = tuple(here[:3])
        if uav:
            true_z = task.passage.height_now()
            self.start = (*off_the_facades(here[:3], self.outline_room)[:2], here[2] if true_z is None else true_z)
        # legs and looks at the height fires are expected at (a UAV; a true height, as the search path's)
        self.z = ARENA.floor_heights[floor] + EXPECTED_FIRE_HEIGHT if uav else self.start[2]
        self.visited: list = [self.start]
        self.skip: list = []
        self.reached: list = []      # viewpoints gone to: not chosen again
        self.looked: list = []       # where it looked around from
        self.watched = np.zeros_like(self.grid.cells, dtype=bool)   # walls the thermal camera looked at
        self.view_range = self.agent.p.explore_view_range if self.agent.p.explore_view_range > 0 else math.inf

    def run(self) -> list:
        """Fire ids found on the floor (empty: none within the budget)."""
        a, p = self.agent, self.agent.p
        end = a.backend.now() + p.explore_budget
        sight = self.start if p.explore_in_sight else None
        if math.dist(self.start[:2], a.position()[:2]) > p.position_tolerance:
            # off the facades first, at the height it came in at, then down: a UAV going down just inside its
            # window would go down beside the wall under the sill (ideal seed 3: two UAVs hit it there)
            self.task.feedback('EXPLORING', f'floor {self.floor}: in off the facades to '
                                            f'({self.start[0]:.1f}, {self.start[1]:.1f})')
            self.task.call_task_or_raise('move', {'waypoint': (self.start, None)})
        if abs(self.z - self.start[2]) > p.position_tolerance:
            self.task.feedback('EXPLORING', f'floor {self.floor}: to the looking height {self.z:.1f} m')
            self.task.call_task_or_raise('move', {'waypoint': ((*self.start[:2], self.z), None)})
        while True:
            found = self.look_around()
            if found or a.backend.now() >= end or len(self.skip) > 2 * MAX_BLOCKED_LEGS:
                break
            legs = next_viewpoint(self.grid, a.position(), p.explore_clearance, p.explore_min_frontier,
                                  self.skip, sight, self.looked, p.explore_view_range,
                                  pass_clearance=p.explore_pass_clearance, view_clearance=p.explore_view_clearance,
                                  outline_clearance=self.outline_room, view_walls=self.outline_room > 0,
                                  min_move=p.position_tolerance, reached=self.reached)
            if legs is None:
                a.backend.loginfo(f'[{self.task.name}] floor {self.floor}: no frontier left to explore '
                                  f'({len(self.looked)} looks, {len(self.skip) // 2} legs blocked; '
                                  f'{self.grid.summary(a.position(), p.explore_clearance)})')
                break
            if not self.go(legs):
                continue
            self.reached.append(legs[-1])
        if not found:
            self.go_back()
        return found

    def look_around(self) -> list:
        """Turn through the headings on the spot; thermal look and laser scan at each. Fire ids found."""
        a, p = self.agent, self.agent.p
        here = self.task._off_the_walls(a.position())      # a UAV turns ~min_wall_clearance off the walls
        self.looked.append(tuple(here[:2]))
        yaws = self.headings(here)
        for k, yaw in enumerate(yaws):
            self.task.feedback('EXPLORING', f'floor {self.floor}: looking {k + 1}/{len(yaws)}')
            a.move_to(self.task, here[:3], yaw, 'turning')
            self.add_scan()
            found = self.task._look_once(self.floor, p.explore_look_time)
            self.add_scan()
            watch(self.grid, self.watched, here, yaw, math.radians(p.forward_camera_fov), self.view_range)
            if found:
                return found
        return []

    def headings(self, here) -> list:
        """The look-around's headings: ~explore_headings round the turn, or (0) the fewest whose views hold
        every wall (laser return) within ~explore_view_range not yet looked at (exploration.headings_to_watch),
        in the order of one turn; the whole turn without a fresh scan. Why (ideal seed 3 with exploration):
        12 looks of 1.5 s and their turns took 35-50 s at every viewpoint, of viewpoints 0.2-0.5 m apart
        that looked at the same walls again; the exploration's budget (300 s) held 6 of them."""
        p = self.agent.p
        n = look_headings(p)
        if p.explore_headings > 0 or not self.add_scan():
            return [here[3] + 2 * math.pi * k / n for k in range(n)]
        width = math.radians(max(1.0, p.forward_camera_fov - LOOK_OVERLAP))
        yaws = headings_to_watch(wall_bearings(self.grid, here, self.watched, self.view_range), width)
        return sorted(yaws, key=lambda y: (y - here[3]) % (2 * math.pi))

    def add_scan(self) -> bool:
        """The latest fresh scan into the grid; False without one."""
        points = self.scans.points()
        if points is not None:
            self.grid.add_scan(self.agent.position()[:2], points)
        return points is not None

    def go(self, legs: list) -> bool:
        """Along the legs (guarded); False (the end skipped from now on) when one is blocked."""
        z = self.z
        for i, (x, y) in enumerate(legs):
            try:
                self.task.feedback('EXPLORING', f'floor {self.floor}: to ({x:.1f}, {y:.1f}) leg {i + 1}/{len(legs)}')
                on_to = self.through((x, y, z))
                self.task.call_task_or_raise('move', {'waypoint': (tuple(on_to), None)})
            except TaskError as e:
                self.agent.backend.logwarn(f'[{self.task.name}] floor {self.floor}: leg to ({x:.1f}, {y:.1f}): {e}: '
                                           f'that viewpoint is not chosen again')
                self.skip += [(x, y), legs[-1]]
                self.visited.append(tuple(self.agent.position()[:3]))    # where the guard held it
                self.add_scan()
                return False
            self.visited.append(tuple(self.agent.position()[:3]))        # where it is (a doorway's passage
        return True                                                        # may end deeper than the leg)

    def through(self, target) -> tuple:
        """Where a leg to target moves on to: through a doorway across it guided by the laser (the UGV), or
        straight (in-sight explorations, UAVs: a doorway there is left alone; the leg guard stops a leg the
        laser finds crossed. Ideal seed 3 on c3_floor_plan_b: a UAV sent through a doorway at its window's
        height, above the doorway's top, held in the passage for 20 s and hit the facade beside it)."""
        if self.agent.p.explore_in_sight:
            return tuple(target)
        return tuple(self.task.passage.doorway(target))

    def go_back(self) -> None:
        """Back to where the exploration started, at the exploration's height (the caller's way out changes
        height there, where the UAV came down): along the grid's free space (exploration.route_to), again
        from where a blocked leg held it (the scans of the hold are in the grid), at most
        MAX_ROUTES_BACK routes; with no route known, back along the points it visited."""
        p = self.agent.p
        for _ in range(MAX_ROUTES_BACK):
            here = self.agent.position()
            if math.dist(self.start[:2], here[:2]) <= p.position_tolerance:
                return
            legs = route_to(self.grid, here, self.start, p.explore_clearance, p.explore_pass_clearance,
                            self.outline_room)
            if legs is None:
                break
            try:
                self._fly_back([(x, y, self.z) for x, y in legs])
                return
            except TaskError as e:
                self.agent.backend.logwarn(f'[{self.task.name}] floor {self.floor}: back from exploring: {e}: '
                                           'a new way back from here')
                self.add_scan()
        here = self.agent.position()
        back = [(q[0], q[1], self.z) for q in reversed(self.visited)]
        while back and math.dist(back[0][:2], here[:2]) <= p.position_tolerance:
            back.pop(0)
        try:
            self._fly_back(back)
        except TaskError as e:    # the search's result stands; the caller's way out starts from here
            self.agent.backend.logwarn(f'[{self.task.name}] floor {self.floor}: back from exploring: {e}')

    def _fly_back(self, points: list) -> None:
        for q in points:
            self.task.feedback('EXPLORING', f'floor {self.floor}: back to where the search started')
            self.task.call_task_or_raise('move', {'waypoint': (tuple(self.through(q)), None)})
