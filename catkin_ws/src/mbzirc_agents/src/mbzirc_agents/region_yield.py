"""Where a hovering UAV steps aside when the region manager breaks a deadlock (pure geometry).

Why: a UAV that waits for a box keeps the box it hovers in; when another UAV waits for a box overlapping
it while this one waits for a box overlapping the other's, neither ever moves (realistic seed 104). The
manager names one of them (shared_regions_manager/deadlock.py) and gives it the other's refused box: it
moves its hover box out of that box, by the shortest straight step along one axis, and the other's
request is then granted.

Rules: the step is straight along x, y or z to just past the box's face (the hover box included, plus
STEP_CLEARANCE: the hover box reserved again at the reached pose, a few centimetres off, must still clear
it); it stays in the arena, at or above `min_z`, at most `max_step` long, and every point of it keeps
`clearance` from the walls that rise to its height (near a wall, or indoors, no step is offered: the robot
declines and the manager asks the other one).
"""
from __future__ import annotations

from typing import List, Sequence

import numpy as np

from mbzirc_arena.boxes import Box
from mbzirc_arena.buildings import in_footprint, standing_at

STEP_LABEL = 'step_aside'  # the region reserved for the step
STEP_CLEARANCE = 0.3      # m past the box's face, beyond the hover box's half side
STEP_SAMPLES = 0.25       # m between the points of a step checked against the walls


def step_aside_targets(p: Sequence[float], hold_half, box: Box, arena: Sequence[float],
                       buildings: Sequence[Sequence[float]], clearance: float, min_z: float,
                       max_step: float) -> List[np.ndarray]:
    """The places (x, y, z) whose hover box (half sides `hold_half`: one number, or x, y, z as the manager
    holds it, grown by the pose error) is out of `box`, reachable from p by one straight step along an axis
    under the rules above, the shortest first (ties: x, y, z; towards the box's min side first)."""
    here = np.asarray(p[:3], dtype=float)
    lo, hi = np.asarray(box[0], dtype=float), np.asarray(box[1], dtype=float)
    half = np.broadcast_to(np.asarray(hold_half, dtype=float), (3,))
    reach = half + STEP_CLEARANCE
    bounds_lo = np.array([arena[0] + half[0], arena[1] + half[1], max(arena[2] + half[2], min_z)])
    bounds_hi = np.array([arena[3] - half[0], arena[4] - half[1], arena[5] - half[2]])
    found = []
    for axis in range(3):
        for side, value in ((0, lo[axis] - reach[axis]), (1, hi[axis] + reach[axis])):
            target = here.copy()
            target[axis] = value
            length = abs(value - here[axis])
            if length > max_step or not np.all((target >= bounds_lo) & (target <= bounds_hi)):
                continue
            if not clear_of_walls(here, target, buildings, clearance):
                continue
            found.append((length, axis, side, target))
    return [t for *_, t in sorted(found, key=lambda f: f[:3])]


def clear_of_walls(a: np.ndarray, b: np.ndarray, buildings: Sequence[Sequence[float]], clearance: float) -> bool:
    """True when every point of the segment a -> b after a keeps `clearance` (xy) from the walls rising to
    its height."""
    n = max(1, int(np.ceil(np.linalg.norm(b - a) / STEP_SAMPLES)))
    for t in np.linspace(1.0 / n, 1.0, n):
        q = a + t * (b - a)
        if in_footprint(q, standing_at(q, buildings), margin=clearance):
            return False
    return True
