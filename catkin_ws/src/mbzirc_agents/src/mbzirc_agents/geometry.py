"""Pure geometry of the agents: boxes, yaw, facade standoff poses, search paths, 2D path planning.

Why pure: region reservation, goal validation and path planning decide whether two UAVs can meet in
the air; they must be testable without ROS.
"""
from __future__ import annotations

import heapq
import math
from typing import Callable, Iterable, Optional, Sequence

import numpy as np

Box = tuple  # (np.ndarray min xyz, np.ndarray max xyz)


# ---- boxes ------------------------------------------------------------------------------------------
def make_box(min_corner: Sequence[float], max_corner: Sequence[float]) -> Box:
    """A box from two corners given in any order (each axis is sorted)."""
    a = np.asarray(min_corner, dtype=float)
    b = np.asarray(max_corner, dtype=float)
    return np.minimum(a, b), np.maximum(a, b)


def boxes_overlap(a: Box, b: Box) -> bool:
    """True when the boxes share volume; boxes that only touch on a face do not overlap."""
    return bool(np.all(a[0] < b[1]) and np.all(b[0] < a[1]))


def swept_box(p0: Sequence[float], p1: Sequence[float], margin: float) -> Box:
    """The box covering the straight flight p0 -> p1, grown by margin on every side."""
    lo, hi = make_box(p0, p1)
    return lo - margin, hi + margin


def column_box(x: float, y: float, z0: float, z1: float, half_side: float) -> Box:
    """A vertical column over (x, y) between z0 and z1: take-off / landing airspace."""
    return make_box((x - half_side, y - half_side, min(z0, z1)), (x + half_side, y + half_side, max(z0, z1)))


def point_in_box(p: Sequence[float], box: Box) -> bool:
    """True when p is inside the box (faces included)."""
    q = np.asarray(p, dtype=float)
    return bool(np.all(q >= box[0]) and np.all(q <= box[1]))


def all_finite(values: Iterable[float]) -> bool:
    """True when no value is NaN or infinite."""
    return all(math.isfinite(v) for v in values)


def check_point(p: Sequence[float], arena: Sequence[float], what: str = 'waypoint') -> Optional[str]:
    """None when p is finite and inside the arena box (x0, y0, z0, x1, y1, z1), else the reason."""
    if not all_finite(p):
        return f'{what} has NaN or infinite coordinates: {tuple(p)}'
    box = make_box(arena[:3], arena[3:])
    if not point_in_box(p, box):
        return (f'{what} ({p[0]:.2f}, {p[1]:.2f}, {p[2]:.2f}) is outside the arena '
                f'{tuple(round(v, 2) for v in arena)}')
    return None


# ---- yaw ----------------------------------------------------------------------------------------------
def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> Optional[float]:
    """Yaw of a quaternion; None for the all-zero quaternion (meaning "keep the current yaw")."""
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n < 1e-9:
        return None
    x, y, z, w = x / n, y / n, z / n, w / n
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quaternion_from_yaw(yaw: float) -> tuple:
    """(x, y, z, w) of a rotation of yaw about z."""
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def wrap_angle(a: float) -> float:
    """a wrapped to (-pi, pi]."""
    return math.atan2(math.sin(a), math.cos(a))


# ---- facades -----------------------------------------------------------------------------------------
def _dist_point_segment(p, a, b) -> float:
    """Distance in the plane from p to the segment a-b."""
    ax, ay, bx, by = a[0], a[1], b[0], b[1]
    dx, dy = bx - ax, by - ay
    t = ((p[0] - ax) * dx + (p[1] - ay) * dy) / max(dx * dx + dy * dy, 1e-12)
    t = min(1.0, max(0.0, t))
    return math.hypot(p[0] - (ax + t * dx), p[1] - (ay + t * dy))


def standing_at(p: Sequence[float], buildings: Sequence[Sequence[float]], clearance: float = 0.5) -> list:
    """The buildings whose walls rise to p's height (top above p[2] - clearance); all of them for a 2D p.

    Why: footprints are 2D, but the one-storey extension is 4.5 m high and the facade D fires above it
    sit at 6-12.5 m. A UAV 1.5 m in front of a facade D fire is inside the extension's footprint; taken as
    a wall there, the extension's edge 0.7 m away pushed a UAV off the hole for good (seed 9, fire D_3).
    """
    if len(p) < 3:
        return list(buildings)
    return [b for b in buildings if b[4] > p[2] - clearance]


def nearest_face(p: Sequence[float], buildings: Sequence[Sequence[float]]) -> tuple:
    """(outward normal (nx, ny), distance) of the building wall nearest to p in the xy plane.

    Buildings are (x_min, y_min, x_max, y_max, height). Ties (a corner) go to the first face found.
    """
    best: tuple = (None, math.inf)
    for b in buildings:
        x0, y0, x1, y1 = b[:4]
        for normal, a, c in (((-1.0, 0.0), (x0, y0), (x0, y1)), ((1.0, 0.0), (x1, y0), (x1, y1)),
                             ((0.0, -1.0), (x0, y0), (x1, y0)), ((0.0, 1.0), (x0, y1), (x1, y1))):
            d = _dist_point_segment(p, a, c)
            if d < best[1] - 1e-9:
                best = (normal, d)
    return best


def facade_standoff(fire: Sequence[float], buildings: Sequence[Sequence[float]], distance: float) -> tuple:
    """((x, y, z), yaw) of a robot `distance` m out from the facade of `fire`, facing the wall."""
    normal, _ = nearest_face(fire, standing_at(fire, buildings))
    if normal is None:
        raise ValueError('no building')
    pos = (fire[0] + normal[0] * distance, fire[1] + normal[1] * distance, fire[2])
    yaw = math.atan2(-normal[1], -normal[0])
    return pos, yaw


def facing_pose(target: Sequence[float], frm: Sequence[float], distance: float) -> tuple:
    """((x, y, z), yaw) `distance` m from target on the side of `frm`, facing target (indoor fires)."""
    dx, dy = frm[0] - target[0], frm[1] - target[1]
    n = math.hypot(dx, dy)
    if n < 1e-6:
        dx, dy, n = 1.0, 0.0, 1.0
    pos = (target[0] + dx / n * distance, target[1] + dy / n * distance, frm[2])
    return pos, math.atan2(-dy, -dx)


def in_footprint(p: Sequence[float], buildings: Sequence[Sequence[float]], margin: float = 0.0) -> bool:
    """True when p (xy) is inside a building footprint grown by margin."""
    return any(b[0] - margin <= p[0] <= b[2] + margin and b[1] - margin <= p[1] <= b[3] + margin
               for b in buildings)


def faces_wall(pos: Sequence[float], yaw: Optional[float], buildings: Sequence[Sequence[float]],
               max_dist: float = 3.5) -> bool:
    """True when a building wall is straight ahead of pos (heading yaw) within max_dist, at pos's height."""
    if yaw is None:
        return False
    for d in np.arange(0.1, max_dist + 1e-9, 0.1):
        q = (pos[0] + d * math.cos(yaw), pos[1] + d * math.sin(yaw))
        if any(b[0] <= q[0] <= b[2] and b[1] <= q[1] <= b[3] and pos[2] <= b[4] for b in buildings):
            return True
    return False


# ---- paths -------------------------------------------------------------------------------------------
def lawnmower(area: Sequence[float], spacing: float, z: float) -> list:
    """Boustrophedon waypoints [(x, y, z)] covering area (x_min, y_min, x_max, y_max), legs along x."""
    x0, y0, x1, y1 = area
    if spacing <= 0:
        raise ValueError('spacing must be > 0')
    n = max(1, int(math.ceil((y1 - y0) / spacing)) + 1)
    ys = np.linspace(y0, y1, n) if n > 1 else [0.5 * (y0 + y1)]
    pts = []
    for i, y in enumerate(ys):
        xs = (x0, x1) if i % 2 == 0 else (x1, x0)
        pts += [(float(xs[0]), float(y), z), (float(xs[1]), float(y), z)]
    return pts


def path_length(points: Sequence[Sequence[float]]) -> float:
    """Length of the polyline through points."""
    return float(sum(np.linalg.norm(np.subtract(b, a)) for a, b in zip(points[:-1], points[1:])))


def segment_hits_rect(a, b, rect, shrink: float = 0.0) -> bool:
    """True when segment a-b crosses the open rectangle (x0, y0, x1, y1) (Liang-Barsky clipping).

    `shrink` > 0 tests against the rectangle made smaller by that much on every side, so that a segment
    that only runs along (or ends on) the border does not count as crossing it despite rounding.
    """
    x0, y0, x1, y1 = rect[0] + shrink, rect[1] + shrink, rect[2] - shrink, rect[3] - shrink
    dx, dy = b[0] - a[0], b[1] - a[1]
    t0, t1 = 0.0, 1.0
    for p, q in ((-dx, a[0] - x0), (dx, x1 - a[0]), (-dy, a[1] - y0), (dy, y1 - a[1])):
        if abs(p) < 1e-12:
            if q <= 0:
                return False
        else:
            t = q / p
            if p < 0:
                t0 = max(t0, t)
            else:
                t1 = min(t1, t)
    return t1 - t0 > 1e-9


_segment_hits_rect = segment_hits_rect  # the former private name, still used by tests


def shortest_path(nodes: Sequence, visible: Callable[[int, int], bool], tie_tol: float = 0.0) -> Optional[list]:
    """Dijkstra over a visibility graph: node indices of the shortest way from nodes[0] to nodes[1].

    Nodes are 2D points; an edge i-j exists when visible(i, j), weighted by its length. A new way to a node
    replaces the known one only when shorter by more than `tie_tol` (so that, of two equal ways, the first
    found is kept). None when nodes[1] cannot be reached.
    """
    dist = {0: 0.0}
    prev: dict = {}
    heap = [(0.0, 0)]
    done = set()
    while heap:
        d, i = heapq.heappop(heap)
        if i in done:
            continue
        done.add(i)
        if i == 1:
            break
        for j in range(len(nodes)):
            if j in done or not visible(i, j):
                continue
            nd = d + math.dist(nodes[i], nodes[j])
            if nd < dist.get(j, math.inf) - tie_tol:
                dist[j] = nd
                prev[j] = i
                heapq.heappush(heap, (nd, j))
    if 1 not in done:
        return None
    path, k = [1], 1
    while k != 0:
        k = prev[k]
        path.append(k)
    return path[::-1]


def plan_2d(start: Sequence[float], goal: Sequence[float], obstacles: Sequence[Sequence[float]],
            clearance: float) -> Optional[list]:
    """Shortest 2D path [(x, y)] from start to goal around rectangular obstacles (visibility graph).

    Obstacles (x0, y0, x1, y1, ...) are grown by clearance; nodes are the grown corners pushed out a
    little further so that paths along a wall do not graze it. None when no path exists (goal inside).
    """
    grown = [(o[0] - clearance, o[1] - clearance, o[2] + clearance, o[3] + clearance) for o in obstacles]
    s, g = (float(start[0]), float(start[1])), (float(goal[0]), float(goal[1]))
    for r in grown:
        if r[0] < g[0] < r[2] and r[1] < g[1] < r[3]:
            return None
    eps = 0.05
    nodes = [s, g]
    for r in grown:
        for cx, cy in ((r[0] - eps, r[1] - eps), (r[2] + eps, r[1] - eps),
                       (r[0] - eps, r[3] + eps), (r[2] + eps, r[3] + eps)):
            if not any(q[0] < cx < q[2] and q[1] < cy < q[3] for q in grown):
                nodes.append((cx, cy))

    def visible(i: int, j: int) -> bool:
        return not any(segment_hits_rect(nodes[i], nodes[j], r) for r in grown)

    path = shortest_path(nodes, visible)
    return None if path is None else [nodes[k] for k in path]
