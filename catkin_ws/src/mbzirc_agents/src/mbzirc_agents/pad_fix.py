"""The GNSS error of a UAV near home, measured by its laser on the buildings' outer walls (pure geometry).

Why: the landing at home is flown on GNSS, whose bias is of the order of a metre and wanders (tens of
seconds), and the reset (refill, new blanket) is given only on the pad: realistic seed 105, UAV 2 landed
three times off its pad and was never refilled (idle 716 s); seeds 111 and 113, landings again. Averaging
the fixes does not remove a bias. But the outline of the buildings is known before the trial (mbzirc_arena)
and from the home pads the horizontal laser sees two of the tower's outer faces nearly square to each other
(facade C, x = 11.4, and facade B and the extension's south wall, y = 6.7): the returns of a face, placed
with the reported pose, lie off its known line by the GNSS error along the face's normal, and two faces
give both axes. The UAL's yaw (the compass's) is taken as right.

Rule (`gnss_error`): for each outer face turned towards the robot (by its reported pose) and standing at the laser's height
(`outline_faces`), the returns within `gate` of its line (the largest error a team allows), away from its
ends by `gate` (a perpendicular face meeting it there spreads its returns across the gate), at least
`min_points` of them spread over `min_span` m: their median offset from the line, then the median of those
within `inlier` of it, is the error along the normal. The faces' errors are solved together by least squares
for the (x, y) error; a direction no face constrains is left at 0 and reported unobserved.
"""
from __future__ import annotations

from typing import Optional, Sequence

import numpy as np
from indoor_localization.outline import outline_faces

from mbzirc_arena.c3 import ARENA

GATE = 2.0          # m: the largest horizontal GNSS error along a face's normal looked for (~4 sigma of 0.5 m)
INLIER = 0.3        # m around the first median: the face's returns (range noise 1 % at 10-25 m)
MIN_POINTS = 8      # returns of a face that make an observation
MIN_SPAN = 2.0      # m along the face they spread over
FACES = outline_faces(ARENA.footprints)


def face_errors(points: np.ndarray, here: Sequence[float], z: float, faces=FACES, gate: float = GATE,
                min_points: int = MIN_POINTS, min_span: float = MIN_SPAN) -> list:
    """[(normal (2,), error along it)] of the outer faces seen in points ((N, 2), the scan's returns placed
    with the reported pose at `here` (x, y), the laser at height z)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    out = []
    for f in faces:
        n = np.asarray(f.normal, dtype=float)
        if f.top <= z or float(n @ np.asarray(here[:2], dtype=float)) - f.offset <= 0.0:
            continue                    # not standing at the laser's height, or not turned towards us
        u = (np.asarray(f.b) - np.asarray(f.a)) / f.length
        d = pts @ n - f.offset
        along = (pts - np.asarray(f.a)) @ u
        sel = (np.abs(d) < gate) & (along > gate) & (along < f.length - gate)
        if sel.sum() < min_points:
            continue
        d, along = d[sel], along[sel]
        m = float(np.median(d))
        keep = np.abs(d - m) < INLIER
        if keep.sum() < min_points or float(np.ptp(along[keep])) < min_span:
            continue
        out.append((n, float(np.median(d[keep]))))
    return out


def gnss_error(observations: Sequence[tuple]) -> tuple:
    """((ex, ey), observed directions 0-2) from face_errors' observations, of one scan or several: the median
    error of each face (its normal), then least squares over the faces; (0, 0) and 0 without any."""
    faces: dict = {}
    for n, e in observations:
        faces.setdefault(tuple(np.round(n, 6)), []).append(e)
    if not faces:
        return np.zeros(2), 0
    a = np.array(list(faces), dtype=float)
    b = np.array([float(np.median(v)) for v in faces.values()])
    return np.linalg.lstsq(a, b, rcond=None)[0], int(np.linalg.matrix_rank(a, tol=0.3))


__all__ = ['face_errors', 'gnss_error', 'GATE']
