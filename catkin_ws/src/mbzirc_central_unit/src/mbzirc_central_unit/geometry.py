"""Routes around the building and through the virtual elevators (pure geometry, no ROS).

A UAV never changes altitude next to the building except inside its virtual elevator, a vertical column
at a tower corner; at a fixed altitude it goes around the footprint of whatever part of the building is
taller than it. This keeps the UAVs separated: each has its own transit altitude and its own elevator.
The building, the floors, the segment-vs-rectangle test and the visibility-graph search are the arena's
(mbzirc_arena): the strategy and the agents route around the same building with the same code.
"""
from __future__ import annotations

import math
from typing import Optional, Sequence

from mbzirc_arena import c3
from mbzirc_arena import routing as R
from mbzirc_arena.buildings import facade_standoff, open_face, standing_at
from mbzirc_arena.c3 import floor_of  # noqa: F401  (the strategy's floor rule is the arena's)

from . import constants as C

Point = tuple[float, float, float]
Pose = tuple[float, float, float, float]  # x, y, z, yaw
Rect = tuple[float, float, float, float]  # xmin, ymin, xmax, ymax

EPS = 1e-6
SHRINK = 1e-4  # m: a segment must enter a rectangle this far to hit it
CORNER_PAD = 0.3  # corner waypoints sit this far outside the inflated rectangle


def obstacle_rect(z: float, margin: float, boxes: Sequence = c3.BUILDING_BOXES,
                  clearance: float = 1.0) -> Optional[Rect]:
    """Footprint (bounding rectangle, inflated by `margin`) of the boxes reaching above z - clearance."""
    rects = [b for b in boxes if b[5] > z - clearance and b[2] < z + clearance]
    if not rects:
        return None
    return (min(b[0] for b in rects) - margin, min(b[1] for b in rects) - margin,
            max(b[3] for b in rects) + margin, max(b[4] for b in rects) + margin)


def inside(p: Sequence[float], r: Rect, tol: float = EPS) -> bool:
    """True if the 2D point is strictly inside the rectangle."""
    return r[0] + tol < p[0] < r[2] - tol and r[1] + tol < p[1] < r[3] - tol


def segment_hits_rect(p: Sequence[float], q: Sequence[float], r: Rect) -> bool:
    """True if the 2D segment p-q passes through the open interior of r, shrunk by SHRINK so that a
    route along the border (or ending on it) does not count."""
    return R.segment_hits_rect(p, q, r, shrink=SHRINK)


def push_out(p: Sequence[float], r: Rect) -> tuple[float, float]:
    """The nearest 2D point on the border of r (plus a pad) when p is inside r, else p itself."""
    if not inside(p, r):
        return (p[0], p[1])
    d = [p[0] - r[0], r[2] - p[0], p[1] - r[1], r[3] - p[1]]
    k = d.index(min(d))
    pad = CORNER_PAD
    return [(r[0] - pad, p[1]), (r[2] + pad, p[1]), (p[0], r[1] - pad), (p[0], r[3] + pad)][k]


def route_2d(p: Sequence[float], q: Sequence[float], r: Optional[Rect]) -> list[tuple[float, float]]:
    """Intermediate 2D waypoints (corners of r) of the shortest way from p to q around r, ends excluded."""
    if r is None or not segment_hits_rect(p, q, r):
        return []
    corners = [(r[0] - CORNER_PAD, r[1] - CORNER_PAD), (r[2] + CORNER_PAD, r[1] - CORNER_PAD),
               (r[2] + CORNER_PAD, r[3] + CORNER_PAD), (r[0] - CORNER_PAD, r[3] + CORNER_PAD)]
    nodes = [tuple(p[:2]), tuple(q[:2])] + corners
    path = R.shortest_path(nodes, lambda i, j: not segment_hits_rect(nodes[i], nodes[j], r), tie_tol=EPS)
    return [] if path is None else [nodes[k] for k in path[1:-1]]


def level_route(p: Point, q: Point, z: float, margin: float = C.ROUTE_MARGIN) -> list[Point]:
    """Waypoints from p to q (q included) at altitude z, around the building."""
    r = obstacle_rect(z, margin)
    start = p
    out: list[Point] = []
    if r is not None and inside(p, r):
        x, y = push_out(p, r)
        start = (x, y, z)
        out.append(start)
    goal_xy = (q[0], q[1])
    if r is not None and inside(q, r):
        goal_xy = push_out(q, r)
    for x, y in route_2d(start, goal_xy, r):
        out.append((x, y, z))
    if goal_xy != (q[0], q[1]):
        out.append((goal_xy[0], goal_xy[1], z))
    out.append((q[0], q[1], q[2]))
    return out


def elevator_points(margin: float = C.ELEVATOR_MARGIN) -> list[tuple[float, float]]:
    """The two virtual elevators: off the opposite (north-west and south-east) corners of the tower.

    .. note:: With the default margin they are the fixed C.ELEVATORS, placed away from the outdoor fire
       holders: a blanket UAV descending on a fire must never wait for an elevator's reserved column.
    """
    if margin == C.ELEVATOR_MARGIN:
        return [tuple(e) for e in C.ELEVATORS]
    t = c3.TOWER_BOX
    return [(t[0] - margin, t[4] + margin), (t[3] + margin, t[1] - margin)]


def elevator_box(index: int, z_low: float, z_high: float, half: float = 1.5,
                 margin: float = C.ELEVATOR_MARGIN) -> tuple[Point, Point]:
    """Min and max corners of the vertical region of elevator `index` between two altitudes."""
    x, y = elevator_points(margin)[index % 2]
    lo, hi = min(z_low, z_high), max(z_low, z_high)
    return (x - half, y - half, max(0.0, lo - 1.0)), (x + half, y + half, hi + 1.0)


def plan_route(start: Point, goal: Point, elevator: int, same_level_tol: float = 0.75) -> list[Point]:
    """Waypoints from start to goal: around the building at the start altitude to the elevator, vertical
    inside it, then around the building at the goal altitude. Without altitude change, one level route."""
    if abs(start[2] - goal[2]) <= same_level_tol:
        z = max(start[2], goal[2])
        path = level_route(start, (goal[0], goal[1], z), z)
        if path[-1][2] != goal[2]:
            path[-1] = goal
        return path
    ex, ey = elevator_points()[elevator % 2]
    path = level_route(start, (ex, ey, start[2]), start[2])
    path.append((ex, ey, goal[2]))
    path += level_route((ex, ey, goal[2]), goal, goal[2])
    return path


# Facade letters by the outward normal of the tower's faces: A north, B south, C west, D east.
FACADE_LETTERS = {(0.0, 1.0): "A", (0.0, -1.0): "B", (-1.0, 0.0): "C", (1.0, 0.0): "D"}


def facade_of(holder: Point, standoff: float = C.FACADE_STANDOFF) -> str:
    """Facade letter of a holder or a facade fire estimate: the facade whose standoff the viewpoint is in
    (mbzirc_arena.buildings.open_face: the nearest wall whose standoff is in the open). Why the nearest, not
    within 0.3 m of a face: an estimate carries the GNSS error of the poses that placed it (realistic seed
    102: one 0.3 m north of facade A counted as facade D, two UAVs hit facade A). Why open: the extension
    hides facade D below 4.5 m (realistic seed 111: an estimate of A_4 1.8 m into the tower, nearer D, got a
    viewpoint inside the extension and was never watered)."""
    p = _at_least(holder, 1.0)
    normal, _ = open_face(p, standing_at(p, c3.FOOTPRINTS), standoff)
    return FACADE_LETTERS[tuple(float(n) for n in normal)]


def viewpoint(holder: Point, standoff: float = C.FACADE_STANDOFF, min_z: float = 1.0) -> Pose:
    """Pose `standoff` metres in front of a facade point, looking at it, at least min_z high: the agents'
    standoff rule (mbzirc_arena.buildings.facade_standoff), out from the facade's known plane."""
    (x, y, z), yaw = facade_standoff(_at_least(holder, min_z), c3.FOOTPRINTS, standoff)
    return (x, y, z, yaw)


def _at_least(p: Point, z_min: float) -> Point:
    return (p[0], p[1], max(p[2], z_min))


def _perimeter_key(holder: Point) -> float:
    """Order along the facades: C south to north, A west to east, D north to south."""
    face = facade_of(holder)
    if face == "C":
        return holder[1]
    if face == "A":
        return 100.0 + holder[0]
    return 200.0 - holder[1]


def facade_search_path(floor: int, holders: Sequence[Point] = c3.FACADE_HOLDERS,
                       standoff: float = C.FACADE_STANDOFF, reverse: bool = False) -> list[Pose]:
    """Viewpoints of every holder of one floor in perimeter order, with corner waypoints between facades."""
    mine = sorted((h for h in holders if floor_of(h[2]) == floor), key=_perimeter_key, reverse=reverse)
    path: list[Pose] = []
    for h in mine:
        vp = viewpoint(h, standoff)
        if path:
            prev = path[-1]
            z = max(prev[2], vp[2])
            for x, y, _ in level_route(prev[:3], vp[:3], z, margin=standoff - 0.3)[:-1]:
                path.append((x, y, z, prev[3]))
        path.append(vp)
    return path


def ground_search_path(start: Sequence[float], altitude: float, candidates: Sequence[Point]) -> list[Pose]:
    """Nearest-neighbour tour over the ground fire places (the layout's) at the search altitude."""
    left = list(candidates)
    cur = (start[0], start[1])
    out: list[Pose] = []
    while left:
        nxt = min(left, key=lambda c: math.dist(cur, c[:2]))
        left.remove(nxt)
        # Two waypoints 0.6 m apart over each holder: the UAV slows down and stops above it, so the fire
        # stays in the narrow downward field of view for the detector's frame filter (> 1 s).
        dx, dy = nxt[0] - cur[0], nxt[1] - cur[1]
        n = math.hypot(dx, dy) or 1.0
        out.append((nxt[0] - 0.3 * dx / n, nxt[1] - 0.3 * dy / n, altitude, 0.0))
        out.append((nxt[0] + 0.3 * dx / n, nxt[1] + 0.3 * dy / n, altitude, 0.0))
        cur = nxt[:2]
    return out


def lawnmower_path(area: Sequence[float] = C.GROUND_SEARCH_AREA, spacing: float = C.GROUND_SWEEP_SPACING,
                   altitude: float = C.GROUND_SEARCH_ALTITUDE) -> list[Pose]:
    """Back-and-forth sweep over a rectangle (x legs), skipping nothing: used for the second ground search."""
    xmin, ymin, xmax, ymax = area
    out: list[Pose] = []
    n = max(1, int(math.ceil((ymax - ymin) / spacing)))
    for i in range(n + 1):
        y = min(ymin + i * spacing, ymax)
        xs = (xmin, xmax) if i % 2 == 0 else (xmax, xmin)
        out.append((xs[0], y, altitude, 0.0))
        out.append((xs[1], y, altitude, 0.0))
    return out


def yaw_towards(p: Sequence[float], q: Sequence[float]) -> float:
    """Heading from p to q in the xy plane."""
    return math.atan2(q[1] - p[1], q[0] - p[0])
