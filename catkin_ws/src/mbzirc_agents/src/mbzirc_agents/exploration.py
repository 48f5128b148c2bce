"""Indoor exploration on sensed free space: where to look next inside a floor nobody told the robot about.

Why: a team knows the building's outline, its floors and the approximate places of its windows and door,
not the interior walls or where the indoor fires are (issue 18). A robot inside a floor therefore builds a
coarse grid of the floor's outline from its own laser (free along each beam, occupied at its return) and
goes to the frontier (free space next to space it has not seen) that is nearest along the free space: a
doorway is a gap in the scan, the free space seen through it is a frontier, so rooms behind interior walls
are reached through their doorways without knowing where they are.

Rules:
- the grid covers the footprint of the building the robot is in (public), `resolution` m cells, each
  unknown, free or occupied; a beam's cells up to its return are free, the return's cell occupied (a
  return outside the footprint, through a window, frees the cells up to the outline only);
- a cell hit by a return is occupied; an occupied cell is free again once CLEAR_SCANS later scans saw
  through it without a return in it (the poses come with a drifting GNSS error: a wall's returns from one
  pose may fall into a doorway seen through from another); within a scan, a hit wins (a wall seen
  edge-on is not freed by a neighbouring beam);
- a robot may stand on free cells at least `clearance` from every occupied cell and inside the footprint
  by `clearance` (the outer walls); the robot's own cell is allowed whatever its clearance (it is there),
  and a robot short of the clearances (its pose moved on it) leaves through the free cells near it no
  nearer the returns nor the outline than its own (`way_out`);
- a frontier cell is such a standable cell with an unknown 4-neighbour; frontier cells that touch form one
  frontier; one with fewer than `min_frontier` cells is noise (a single missed beam);
- the next viewpoint is a cell of a frontier at least `view_clearance` from every return when there is
  one (a thermal camera near a wall sees a strip of it), else any, the cheapest along the cells at least
  `pass_clearance` from every return (Dijkstra over 8-neighbours; a cell under `clearance` costs up to
  NARROW_COST times more: a doorway between noisy jambs holds no cell 0.8 m clear on a 0.25 m grid, and
  its passage is centred by the laser); its path is cut into straight legs, each a line of standable
  cells or of the path's own (`straight_legs`), so that every leg is one the leg guard checks;
- with a view range, standable cells farther than it from every point the robot looked from count as
  frontiers too (the laser sees a whole room from its door, the thermal camera a fire only nearer), and,
  when asked (a UAV, kept off the outline), standable cells within half of it of a laser return (a wall)
  farther than it from every such point;
- `sight_of` limits a search to what is in straight sight of its start when a caller asks for it (a
  UAV in a window's room, which must come back out the same way).
Pure geometry here (no ROS); the task using it is tasks/explore.py.
"""
from __future__ import annotations

import heapq
import math
from typing import Iterable, Optional, Sequence

import numpy as np

UNKNOWN, FREE, OCCUPIED = 0, 1, 2
NEIGHBOURS_4 = ((1, 0), (-1, 0), (0, 1), (0, -1))
NEIGHBOURS_8 = NEIGHBOURS_4 + ((1, 1), (1, -1), (-1, 1), (-1, -1))

Cell = tuple[int, int]
# scans that see through an occupied cell (and none hits it) before it is free again: returns placed with a
# drifting GNSS pose close a doorway seen from elsewhere (realistic seed 104: the UGV's ground floor, 'no
# frontier left' with the east room's doorway never passed); one look around is 2 scans per heading
CLEAR_SCANS = 3
NARROW_COST = 4.0   # extra cost factor of a path cell with only pass_clearance (next_viewpoint)


class FloorGrid:
    """What the robot has seen of one floor: unknown / free / occupied cells over the building's footprint.

    Args:
        bounds: x_min, y_min, x_max, y_max of the footprint (m, arena frame).
        resolution: m per cell side.
    """

    def __init__(self, bounds: Sequence[float], resolution: float = 0.25) -> None:
        self.x0, self.y0, x1, y1 = (float(v) for v in bounds[:4])
        self.x1, self.y1 = x1, y1            # the footprint's far sides (the grid's last cells may pass them)
        if x1 <= self.x0 or y1 <= self.y0 or resolution <= 0:
            raise ValueError(f'bad footprint {tuple(bounds[:4])} or resolution {resolution}')
        self.res = float(resolution)
        self.nx = max(1, int(math.ceil((x1 - self.x0) / self.res)))
        self.ny = max(1, int(math.ceil((y1 - self.y0) / self.res)))
        self.cells = np.full((self.nx, self.ny), UNKNOWN, dtype=np.int8)
        self.misses = np.zeros((self.nx, self.ny), dtype=np.int32)   # scans through an occupied cell since its hit

    # ---- cells and points ------------------------------------------------------------------------------
    def cell(self, x: float, y: float) -> Optional[Cell]:
        i, j = int(math.floor((x - self.x0) / self.res)), int(math.floor((y - self.y0) / self.res))
        return (i, j) if 0 <= i < self.nx and 0 <= j < self.ny else None

    def centre(self, c: Cell) -> tuple[float, float]:
        return self.x0 + (c[0] + 0.5) * self.res, self.y0 + (c[1] + 0.5) * self.res

    # ---- sensing ---------------------------------------------------------------------------------------
    def add_scan(self, origin: Sequence[float], points: np.ndarray) -> None:
        """Add one scan's returns (N x 2, arena frame) seen from origin (x, y): each beam passes the cells of
        its samples every half cell from the origin (up to the first outside the footprint: out through a
        window, nothing more of this floor), and hits its end's cell. Vectorised over every sample of the
        scan at once (a look adds ~720 beams of up to 80 samples each; one cell lookup per sample in Python
        cost tens of milliseconds per scan)."""
        ox, oy = float(origin[0]), float(origin[1])
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        pts = pts[np.isfinite(pts).all(axis=1)]
        if not len(pts):
            return
        rel = pts - (ox, oy)
        steps = (np.hypot(rel[:, 0], rel[:, 1]) / (0.5 * self.res)).astype(int)
        beam = np.repeat(np.arange(len(pts)), steps)
        k = np.arange(beam.size) - np.repeat(np.cumsum(steps) - steps, steps)      # sample index along its beam
        t = k / np.maximum(steps, 1)[beam]
        i = np.floor((ox + rel[beam, 0] * t - self.x0) / self.res).astype(int)
        j = np.floor((oy + rel[beam, 1] * t - self.y0) / self.res).astype(int)
        out = (i < 0) | (i >= self.nx) | (j < 0) | (j >= self.ny)
        first_out = np.full(len(pts), np.iinfo(np.int64).max)
        np.minimum.at(first_out, beam[out], k[out])
        keep = k < first_out[beam]
        passed = np.unique(i[keep] * self.ny + j[keep])
        ei = np.floor((pts[:, 0] - self.x0) / self.res).astype(int)
        ej = np.floor((pts[:, 1] - self.y0) / self.res).astype(int)
        inside = (ei >= 0) & (ei < self.nx) & (ej >= 0) & (ej < self.ny)
        hits = np.unique(ei[inside] * self.ny + ej[inside])
        # a wall seen edge-on is not freed by a neighbouring beam of the same scan
        freed = np.setdiff1d(passed, hits, assume_unique=True)
        cells, misses = self.cells.reshape(-1), self.misses.reshape(-1)        # views
        state = cells[freed]
        cells[freed[state == UNKNOWN]] = FREE
        occ = freed[state == OCCUPIED]
        misses[occ] += 1
        cells[occ[misses[occ] >= CLEAR_SCANS]] = FREE
        cells[hits] = OCCUPIED
        misses[hits] = 0

    # ---- where the robot may stand ---------------------------------------------------------------------
    def to_outline(self) -> np.ndarray:
        """m from each cell's centre to the footprint's outline (0 beyond it). Why: the grid's last cells
        pass the footprint's far sides by up to a cell; counted from the grid's edge, a cell 0.6 m from the
        outline was 0.8 m clear (ideal seed 3 with exploration: a UAV sent 0.5 m from the wall beside its
        window crashed into it)."""
        xs = self.x0 + (np.arange(self.nx) + 0.5) * self.res
        ys = self.y0 + (np.arange(self.ny) + 0.5) * self.res
        dx = np.minimum(xs - self.x0, self.x1 - xs)[:, None]
        dy = np.minimum(ys - self.y0, self.y1 - ys)[None, :]
        return np.clip(np.minimum(dx, dy), 0.0, None)

    def clearance(self) -> np.ndarray:
        """m from each cell's centre to the nearest occupied cell's centre and to the outline (inf: none)."""
        ii, jj = np.meshgrid(np.arange(self.nx), np.arange(self.ny), indexing='ij')
        d2 = np.full((self.nx, self.ny), np.inf)
        for oi, oj in np.argwhere(self.cells == OCCUPIED):
            np.minimum(d2, (ii - oi) ** 2 + (jj - oj) ** 2, out=d2)
        return np.minimum(np.sqrt(d2) * self.res, self.to_outline())

    def standable(self, clearance: float, here: Optional[Cell] = None, clear: Optional[np.ndarray] = None) -> np.ndarray:
        """Boolean grid of the free cells at least clearance from every occupied cell and from the outline
        (`clear`: the grid's clearance() when the caller has it)."""
        clear = self.clearance() if clear is None else clear
        ok = (self.cells == FREE) & (clear >= clearance - 1e-9)
        if here is not None:
            ok[here] = True
        return ok

    def summary(self, here: Sequence[float], clearance: float) -> str:
        """What an operator reads when the search ends: the cells seen free and occupied, those a robot
        may stand on, and the robot's own clearance (a return near it keeps it from every neighbour)."""
        clear = self.clearance()
        c = self.cell(here[0], here[1])
        own = (f'{clear[c]:.2f} m clear, {self.to_outline()[c]:.2f} m from the outline' if c is not None
               else 'outside the grid')
        return (f'{int((self.cells == FREE).sum())} cells free, {int((self.cells == OCCUPIED).sum())} occupied, '
                f'{int(self.standable(clearance, clear=clear).sum())} standable; at ({here[0]:.2f}, {here[1]:.2f}) '
                f'{own}')

    def frontier_cells(self, ok: np.ndarray) -> set:
        """Standable cells with an unknown 4-neighbour."""
        out = set()
        for i, j in np.argwhere(ok):
            for di, dj in NEIGHBOURS_4:
                a, b = i + di, j + dj
                if 0 <= a < self.nx and 0 <= b < self.ny and self.cells[a, b] == UNKNOWN:
                    out.add((int(i), int(j)))
                    break
        return out

    def line_free(self, ok: np.ndarray, a: Cell, b: Cell) -> bool:
        """True if every cell on the straight line a-b is standable."""
        n = max(abs(b[0] - a[0]), abs(b[1] - a[1])) * 2 + 1
        for k in range(n + 1):
            t = k / n
            c = (int(round(a[0] + (b[0] - a[0]) * t)), int(round(a[1] + (b[1] - a[1]) * t)))
            if not ok[c]:
                return False
        return True


def frontiers(grid: FloorGrid, ok: np.ndarray, min_frontier: int) -> list[set]:
    """The frontiers (touching frontier cells, 8-neighbours) of at least min_frontier cells."""
    left = grid.frontier_cells(ok)
    groups = []
    while left:
        seed = left.pop()
        group, todo = {seed}, [seed]
        while todo:
            i, j = todo.pop()
            for di, dj in NEIGHBOURS_8:
                c = (i + di, j + dj)
                if c in left:
                    left.discard(c)
                    group.add(c)
                    todo.append(c)
        if len(group) >= min_frontier:
            groups.append(group)
    return groups


def paths_from(ok: np.ndarray, start: Cell, cost: Optional[np.ndarray] = None) -> tuple[dict, dict]:
    """Cheapest paths over standable cells (8-neighbours) from start: (parents, costs). A step costs its
    length times `cost` of the cell it enters (1 without)."""
    parent, best = {start: None}, {start: 0.0}
    heap = [(0.0, start)]
    nx, ny = ok.shape
    while heap:
        d, (i, j) = heapq.heappop(heap)
        if d > best[(i, j)]:
            continue
        for di, dj in NEIGHBOURS_8:
            c = (i + di, j + dj)
            if 0 <= c[0] < nx and 0 <= c[1] < ny and ok[c]:
                nd = d + math.hypot(di, dj) * (1.0 if cost is None else float(cost[c]))
                if nd < best.get(c, math.inf):
                    best[c], parent[c] = nd, (i, j)
                    heapq.heappush(heap, (nd, c))
    return parent, best


def straight_legs(grid: FloorGrid, ok: np.ndarray, cells: list, ends: Optional[np.ndarray] = None) -> list:
    """The cell path cut into the fewest straight legs (greedy: each leg goes as far as a free line does,
    ending on an `ends` cell when one is that far: a leg ending in a doorway leaves the robot between
    its jambs, where the leg guard holds the next leg)."""
    legs, k = [], 0
    while k < len(cells) - 1:
        reach = [m for m in range(len(cells) - 1, k, -1) if grid.line_free(ok, cells[k], cells[m])]
        good = [m for m in reach if ends is None or m == len(cells) - 1 or ends[cells[m]]]
        far = good[0] if good else reach[0] if reach else k + 1
        legs.append(cells[far])
        k = far
    return legs


def next_viewpoint(grid: FloorGrid, here: Sequence[float], clearance: float, min_frontier: int = 3,
                   skip: Iterable = (), sight_of: Optional[Sequence[float]] = None,
                   viewed: Sequence = (), view_range: float = 0.0, pass_clearance: Optional[float] = None,
                   view_clearance: float = 0.0, outline_clearance: float = 0.0,
                   view_walls: bool = False, min_move: float = 0.0, reached: Iterable = ()) -> Optional[list]:
    """The legs [(x, y), ...] to the next viewpoint, or None when no frontier is reachable.

    The viewpoint is a frontier's cell (or, with viewed and view_range > 0, a standable cell farther than
    view_range from every viewed point (x, y): seen by the laser, not yet near enough for the thermal
    camera), preferring cells at least view_clearance from every return (a camera near a wall sees a strip
    of it), then the cheapest along the free space. Paths keep `clearance` where they can and
    `pass_clearance` (default: clearance) at least: a doorway 2 m wide holds no cell 0.8 m clear of the
    noisy returns of its jambs on a 0.25 m grid, and its passage is centred by the laser; a narrow cell
    costs up to NARROW_COST times more, and a leg is a straight line of clear cells or of the path's own.
    skip: (x, y) points neither to choose nor to pass (a blocked leg's end); sight_of: only cells in a
    straight line of clear cells from this point count (the point's own cell counts as clear: it was
    flown to). Every cell but the robot's own keeps `clearance` from the footprint's outline (a door is
    not this search's to pass), and outline_clearance when more, whatever the laser sees there (a UAV's laser plane looks out through a window and never sees the wall
    under its sill: ideal seed 3 with exploration, two UAVs sent beside their window hit it). view_walls
    (with view_range): cells near laser returns farther than view_range from every viewed point are
    viewpoints too (near_unviewed_walls): kept off the outline, the standable cells beyond view_range no
    longer bring the camera near the outer walls. min_move: no viewpoint nearer than this to here (a robot
    there already, by its arrival tolerance, would not move and see the same again: the on-demand
    ugv_gnss_denied rostest, a frontier cell 0.2 m from the UGV chosen 100 times in 100 s); reached: (x, y)
    viewpoints gone to before, not chosen again (a frontier the laser cannot resolve from there: a cell it
    never sees, beside or under the robot), still passed."""
    start = grid.cell(here[0], here[1])
    if start is None:
        return None
    space = _Walkable(grid, start, clearance, pass_clearance, outline_clearance, skip)
    ok, passable, clear, banned = space.ok, space.passable, space.clear, space.banned
    origin = grid.cell(sight_of[0], sight_of[1]) if sight_of is not None else None
    in_sight = ok.copy()
    if origin is not None:
        in_sight[origin] = True
    parent, costs = paths_from(passable, start, space.cost)
    targets = [c for group in frontiers(grid, passable, min_frontier) for c in group]
    if view_range > 0:
        targets += unviewed(grid, passable, viewed, view_range)
        if view_walls:
            targets += near_unviewed_walls(grid, passable, viewed, view_range)
    best = None
    done = {grid.cell(p[0], p[1]) for p in reached} - {None}
    for c in set(targets):
        if c not in parent or c in banned or c in done or c == start \
                or math.dist(grid.centre(c), here[:2]) < min_move:
            continue
        if origin is not None and not grid.line_free(in_sight, origin, c):
            continue
        rank = (clear[c] < view_clearance, costs[c])
        if best is None or rank < best[0]:
            best = (rank, c)
    if best is None:
        return None
    return space.legs(parent, best[1])


def route_to(grid: FloorGrid, here: Sequence[float], goal: Sequence[float], clearance: float,
             pass_clearance: Optional[float] = None, outline_clearance: float = 0.0) -> Optional[list]:
    """The legs [(x, y), ...] from here to goal over the sensed free space, kept and costed as next_viewpoint's
    (the goal's own cell counts as standable: the robot stood there), or None when no way is known. Why
    (realistic seed 112 with exploration, GNSS denied): going back to where the search started along the
    points it had visited took a UAV to one where a leg had been blocked, beside a doorway's jamb; held
    there, it left from the doorway and climbed to its window's height into the doorway's top."""
    start, end = grid.cell(here[0], here[1]), grid.cell(goal[0], goal[1])
    if start is None or end is None:
        return None
    if start == end:
        return []
    space = _Walkable(grid, start, clearance, pass_clearance, outline_clearance, ())
    space.ok[end] = space.passable[end] = True
    parent, _ = paths_from(space.passable, start, space.cost)
    if end not in parent:
        return None
    legs = space.legs(parent, end)
    if legs:
        legs[-1] = (float(goal[0]), float(goal[1]))   # the goal itself, not its cell's centre
    return legs


class _Walkable:
    """Where a robot at `start` may stand (ok) and pass (passable), what a step costs, by the rules of the
    module's docstring: shared by next_viewpoint and route_to."""

    def __init__(self, grid: FloorGrid, start: Cell, clearance: float, pass_clearance: Optional[float],
                 outline_clearance: float, skip: Iterable) -> None:
        self.grid = grid
        clear = self.clear = grid.clearance()
        narrow = clearance if pass_clearance is None else min(pass_clearance, clearance)
        ok = self.ok = grid.standable(clearance, here=start, clear=clear)
        passable = self.passable = grid.standable(narrow, here=start, clear=clear)
        outline = grid.to_outline()
        room = max(outline_clearance, clearance)
        inside = outline >= room - 1e-9   # no doorway to pass there
        inside[start] = True
        ok &= inside
        passable &= inside
        out_of_room = way_out(grid, start, clear, outline, narrow, room) & ~passable
        passable |= out_of_room
        self.banned = {grid.cell(p[0], p[1]) for p in skip} - {None, start}
        for c in self.banned:        # neither a target nor a cell to pass: a leg to it was found blocked
            ok[c] = passable[c] = False
        self.cost = 1.0 + NARROW_COST * np.clip((clearance - clear) / max(clearance - narrow, 1e-6), 0.0, 1.0)
        self.cost[out_of_room] = 1.0 + 2 * NARROW_COST

    def legs(self, parent: dict, end: Cell) -> list:
        """The straight legs (cell centres) of the cheapest path to end (paths_from's parents)."""
        cells, c = [], end
        while c is not None:
            cells.append(c)
            c = parent[c]
        cells.reverse()
        on_path = self.ok.copy()
        for i, j in cells:           # a leg may pass narrow cells only beside the path's own
            sl = (slice(max(0, i - 1), i + 2), slice(max(0, j - 1), j + 2))
            on_path[sl] |= self.passable[sl]
        return [self.grid.centre(c) for c in straight_legs(self.grid, on_path, cells, ends=self.ok)]


def way_out(grid: FloorGrid, start: Cell, clear: np.ndarray, outline: np.ndarray, pass_clearance: float,
            room: float) -> np.ndarray:
    """Cells a robot standing short of the clearances may cross to reach them: free, no nearer the laser's
    returns nor the outline than its own cell (short of pass_clearance and room), and within the distance
    it is short by (plus two cells) of it. Why (the on-demand GNSS-denied indoor rostest, facade D's
    window): its pose moves when the source turns from GNSS to SLAM, by the GNSS error (0.8 m there), and a
    robot 0.9 m from the outline by its new pose, 1.75 m asked, had no cell around it to leave by: 'no
    frontier left' after one look, the fire 4.8 m away."""
    own_clear, own_outline = float(clear[start]), float(outline[start])
    short = max(pass_clearance - own_clear, room - own_outline, 0.0)
    if short <= 0.0:
        return np.zeros_like(clear, dtype=bool)
    reach = short + 2 * grid.res
    ii, jj = np.meshgrid(np.arange(grid.nx), np.arange(grid.ny), indexing='ij')
    near = ((ii - start[0]) ** 2 + (jj - start[1]) ** 2) * grid.res ** 2 <= reach ** 2
    return ((grid.cells == FREE) & near & (clear >= min(pass_clearance, own_clear) - 1e-9)
            & (outline >= min(room, own_outline) - 1e-9))


def unviewed(grid: FloorGrid, ok: np.ndarray, viewed: Sequence, view_range: float) -> list:
    """Standable cells farther than view_range from every viewed point (x, y)."""
    far = ok.copy()
    ii, jj = np.meshgrid(np.arange(grid.nx), np.arange(grid.ny), indexing='ij')
    xs, ys = grid.x0 + (ii + 0.5) * grid.res, grid.y0 + (jj + 0.5) * grid.res
    for v in viewed:
        far &= (xs - v[0]) ** 2 + (ys - v[1]) ** 2 > view_range ** 2
    return [(int(i), int(j)) for i, j in np.argwhere(far)]


def near_unviewed_walls(grid: FloorGrid, ok: np.ndarray, viewed: Sequence, view_range: float) -> list:
    """Standable cells within half view_range of an occupied cell that is farther than view_range
    from every viewed point (x, y): a wall the laser saw, the thermal camera not near enough. Why (ideal
    seed 3 with exploration, facade A's window of floor 1): a UAV kept off the facades saw the room whole
    from one look, every standable cell within view_range of it, while the room's far wall, where a fire
    may be, was 3.9 m away."""
    occupied = np.argwhere(grid.cells == OCCUPIED)
    if len(occupied) == 0:
        return []
    wx, wy = grid.x0 + (occupied[:, 0] + 0.5) * grid.res, grid.y0 + (occupied[:, 1] + 0.5) * grid.res
    far = np.ones(len(occupied), dtype=bool)
    for v in viewed:
        far &= (wx - v[0]) ** 2 + (wy - v[1]) ** 2 > view_range ** 2
    ii, jj = np.meshgrid(np.arange(grid.nx), np.arange(grid.ny), indexing='ij')
    xs, ys = grid.x0 + (ii + 0.5) * grid.res, grid.y0 + (jj + 0.5) * grid.res
    near = np.zeros_like(ok)
    reach = (0.5 * view_range) ** 2             # well within: a step that sees more than the one wall cell
    for x, y in zip(wx[far], wy[far]):
        near |= (xs - x) ** 2 + (ys - y) ** 2 <= reach
    return [(int(i), int(j)) for i, j in np.argwhere(near & ok)]


def wall_bearings(grid: FloorGrid, here: Sequence[float], watched: np.ndarray, view_range: float) -> np.ndarray:
    """Bearings (rad) from here of the occupied cells within view_range not yet `watched`."""
    cells = np.argwhere((grid.cells == OCCUPIED) & ~watched)
    if len(cells) == 0:
        return np.zeros(0)
    dx = grid.x0 + (cells[:, 0] + 0.5) * grid.res - here[0]
    dy = grid.y0 + (cells[:, 1] + 0.5) * grid.res - here[1]
    near = dx ** 2 + dy ** 2 <= view_range ** 2
    return np.arctan2(dy[near], dx[near])


def headings_to_watch(bearings: np.ndarray, width: float) -> list:
    """The fewest headings whose views (width rad wide, centred on each) hold every bearing: greedy from
    the widest gap between bearings round the turn."""
    if len(bearings) == 0:
        return []
    b = np.sort(np.mod(bearings, 2 * math.pi))
    gaps = np.diff(np.concatenate([b, [b[0] + 2 * math.pi]]))
    first = (int(np.argmax(gaps)) + 1) % len(b)          # the bearing after the widest gap
    ordered = np.mod(np.roll(b, -first) - b[first], 2 * math.pi) + b[first]
    out, k = [], 0
    while k < len(ordered):
        out.append(float(ordered[k] + width / 2))
        k = int(np.searchsorted(ordered, ordered[k] + width, side='right'))
    return [math.atan2(math.sin(h), math.cos(h)) for h in out]


def watch(grid: FloorGrid, watched: np.ndarray, here: Sequence[float], heading: float, fov: float,
          view_range: float) -> None:
    """Marks the occupied cells within view_range and fov (rad, both ways half) of heading from here watched."""
    cells = np.argwhere(grid.cells == OCCUPIED)
    if len(cells) == 0:
        return
    dx = grid.x0 + (cells[:, 0] + 0.5) * grid.res - here[0]
    dy = grid.y0 + (cells[:, 1] + 0.5) * grid.res - here[1]
    off = np.arctan2(dy, dx) - heading
    off = np.arctan2(np.sin(off), np.cos(off))
    seen = (dx ** 2 + dy ** 2 <= view_range ** 2) & (np.abs(off) <= fov / 2)
    watched[cells[seen, 0], cells[seen, 1]] = True


__all__ = ['FloorGrid', 'frontiers', 'next_viewpoint', 'straight_legs', 'UNKNOWN', 'FREE', 'OCCUPIED']
