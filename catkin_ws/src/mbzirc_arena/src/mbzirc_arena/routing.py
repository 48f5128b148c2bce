"""2D routing around rectangles (building footprints, interior walls): segment tests and shortest paths.

Why shared: the strategy plans the routes it sends and the agents check and fly them; routing around the
same building with different code let a route the strategy thought clear graze a wall.
"""
from __future__ import annotations

import heapq
import math
from typing import Callable, Optional, Sequence

import numpy as np


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


def path_length(points: Sequence[Sequence[float]]) -> float:
    """Length of the polyline through points."""
    return float(sum(np.linalg.norm(np.subtract(b, a)) for a, b in zip(points[:-1], points[1:])))
