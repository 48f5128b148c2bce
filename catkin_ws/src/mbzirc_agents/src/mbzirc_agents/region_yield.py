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

The boxes of a step (`step_aside_moves`) are the hover box *as the manager holds it*, moved along the step's
axis only: the step box covers it from where it is to where it ends, the new hover box is it, moved. Why
(realistic seed 108): a UAV hovering over its pad holds a box placed over the pad, grown in z only
(pose_error_boxes.py), which touches the neighbouring pad's hold box; a step box swept around the reported
pose and grown by the pose error sideways overlapped the neighbour's hold where the held box did not, so no
step was ever granted and both UAVs waited 360 s. A straight step along one axis moves the UAV by that
much along that axis only (its set-point moves along it; the GNSS error wanders slowly), so the held box's
extent across the axis stays right.
"""
from __future__ import annotations

from typing import List, Sequence, Tuple

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
    half = np.broadcast_to(np.asarray(hold_half, dtype=float), (3,))
    held = (here - half, here + half)
    return [t for t, _, _ in step_aside_moves(here, held, box, arena, buildings, clearance, min_z, max_step)]


def step_aside_moves(p: Sequence[float], held: Box, box: Box, arena: Sequence[float],
                     buildings: Sequence[Sequence[float]], clearance: float, min_z: float,
                     max_step: float) -> List[Tuple[np.ndarray, Box, Box]]:
    """(target, step box, new hover box) of every step out of `box` for a UAV at p whose hover box is
    `held` (as the manager holds it), under the rules above, the shortest first (ties: x, y, z; towards
    the box's min side first). The step box is `held` stretched along the step's axis to the new hover
    box, which is `held` moved along that axis."""
    here = np.asarray(p[:3], dtype=float)
    lo, hi = np.asarray(box[0], dtype=float), np.asarray(box[1], dtype=float)
    h_lo, h_hi = np.asarray(held[0], dtype=float), np.asarray(held[1], dtype=float)
    a_lo, a_hi = np.asarray(arena[:3], dtype=float), np.asarray(arena[3:6], dtype=float)
    found = []
    for axis in range(3):
        # the held box's face just past the box's face, on either side
        for side, shift in ((0, lo[axis] - STEP_CLEARANCE - h_hi[axis]), (1, hi[axis] + STEP_CLEARANCE - h_lo[axis])):
            move = np.zeros(3)
            move[axis] = shift
            target, new_lo, new_hi = here + move, h_lo + move, h_hi + move
            if abs(shift) > max_step or np.any(new_lo < a_lo - 1e-9) or np.any(new_hi > a_hi + 1e-9) \
                    or target[2] < min_z:
                continue
            if not clear_of_walls(here, target, buildings, clearance):
                continue
            step = (np.minimum(h_lo, new_lo), np.maximum(h_hi, new_hi))
            found.append((abs(shift), axis, side, target, step, (new_lo, new_hi)))
    return [(t, step, new) for *_, t, step, new in sorted(found, key=lambda f: f[:3])]


def clear_of_walls(a: np.ndarray, b: np.ndarray, buildings: Sequence[Sequence[float]], clearance: float) -> bool:
    """True when every point of the segment a -> b after a keeps `clearance` (xy) from the walls rising to
    its height."""
    n = max(1, int(np.ceil(np.linalg.norm(b - a) / STEP_SAMPLES)))
    for t in np.linspace(1.0 / n, 1.0, n):
        q = a + t * (b - a)
        if in_footprint(q, standing_at(q, buildings), margin=clearance):
            return False
    return True
