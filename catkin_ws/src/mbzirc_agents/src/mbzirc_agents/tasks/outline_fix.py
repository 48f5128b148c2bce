"""A UAV's horizontal GNSS error measured by its laser on the buildings' known outline, for a task that must
place itself against the buildings (the pad landing, a facade fire's standoffs): pad_fix's geometry over a
few scans.

Why: goals near the buildings are flown on GNSS, whose bias is of the order of a metre and wanders over tens of
seconds, while the outline of the buildings is known before the trial. The error along the normal of each
outer face in the laser's view is measured, and a goal placed from the known outline is moved by it (the goal
in the GNSS frame of the moment).
"""
from __future__ import annotations

from typing import Optional, Sequence

from ..pad_fix import face_errors, gnss_error

FIX_TIME = 0.6       # s of scans (10 Hz) whose observations make one fix
LASER_HEIGHT = 0.1   # m of the laser over the reported z (base_link -> laser_link)


def laser_gnss_error(task, guard, what: str) -> Optional[tuple]:
    """(ex, ey) of the reported pose, GNSS less truth, by the laser on the buildings' outline (pad_fix), over
    FIX_TIME s of the scans of `guard` (a LegGuard of the task); an unobserved direction 0; None without any
    observation (logged: the goal is then flown on GNSS)."""
    a = task.agent
    obs, end = [], a.backend.now() + FIX_TIME
    while True:
        points = guard.points()
        if points is not None:
            here = a.position()
            obs += face_errors(points, here[:2], here[2] + LASER_HEIGHT)
        if a.backend.now() >= end:
            break
        task.sleep(0.1)
    err, seen = gnss_error(obs)
    if not seen:
        a.backend.logwarn(f'[{task.name}] {what}: no outer wall of the buildings in the laser\'s view: flown on '
                          'GNSS')
        return None
    a.backend.loginfo(f'[{task.name}] {what}: GNSS error by the laser on the outline ({err[0]:.2f}, '
                      f'{err[1]:.2f}) m, {seen} direction(s) observed')
    return float(err[0]), float(err[1])


def shifted(point: Sequence[float], err: Optional[tuple]) -> tuple:
    """A point placed from the known outline, in the GNSS frame of the error `err` (unchanged without one)."""
    p = tuple(float(v) for v in point)
    return p if err is None else (p[0] + err[0], p[1] + err[1], *p[2:])
