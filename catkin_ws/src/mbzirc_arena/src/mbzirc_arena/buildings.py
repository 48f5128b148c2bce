"""Rules on building footprints: which walls rise to a height, the nearest wall, inside or not, kind of a fire.

Footprints are (x_min, y_min, x_max, y_max, top): the outline of a building and the height of its roof
(`Building.footprint`). Every robot and the central unit decide with these same rules.
"""
from __future__ import annotations

import math
from typing import Sequence

from . import messages as M


def standing_at(p: Sequence[float], footprints: Sequence[Sequence[float]], clearance: float = 0.5) -> list:
    """The buildings whose walls rise to p's height (top above p[2] - clearance); all of them for a 2D p.

    Rule: a wall counts only up to its roof. The one-storey extension is 4.5 m high and the facade D fires
    above it sit at 6-12.5 m: a UAV in front of them is inside the extension's footprint, above its roof.
    """
    if len(p) < 3:
        return list(footprints)
    return [b for b in footprints if b[4] > p[2] - clearance]


def dist_point_segment(p, a, b) -> float:
    """Distance in the plane from p to the segment a-b."""
    ax, ay, bx, by = a[0], a[1], b[0], b[1]
    dx, dy = bx - ax, by - ay
    t = ((p[0] - ax) * dx + (p[1] - ay) * dy) / max(dx * dx + dy * dy, 1e-12)
    t = min(1.0, max(0.0, t))
    return math.hypot(p[0] - (ax + t * dx), p[1] - (ay + t * dy))


def nearest_face(p: Sequence[float], footprints: Sequence[Sequence[float]]) -> tuple:
    """(outward normal (nx, ny), distance) of the building wall nearest to p in the xy plane.

    Ties (a corner) go to the first face found; (None, inf) without buildings.
    """
    best: tuple = (None, math.inf)
    for b in footprints:
        x0, y0, x1, y1 = b[:4]
        for normal, a, c in (((-1.0, 0.0), (x0, y0), (x0, y1)), ((1.0, 0.0), (x1, y0), (x1, y1)),
                             ((0.0, -1.0), (x0, y0), (x1, y0)), ((0.0, 1.0), (x0, y1), (x1, y1))):
            d = dist_point_segment(p, a, c)
            if d < best[1] - 1e-9:
                best = (normal, d)
    return best


def open_face(p: Sequence[float], footprints: Sequence[Sequence[float]], distance: float) -> tuple:
    """(outward normal (nx, ny), foot (x, y): p's nearest point on it) of the nearest wall of footprints whose
    point `distance` m out from the foot lies outside every footprint; the nearest wall when none does;
    (None, None) without buildings. Why: a facade fire estimate carries the GNSS error of the poses that
    placed it, and near a corner the nearest wall may be one another building hides (the tower's east face
    below the extension's roof: realistic seed 111), whose standoff lies inside that building."""
    faces = []
    for b in footprints:
        x0, y0, x1, y1 = b[:4]
        for normal, a, c in (((-1.0, 0.0), (x0, y0), (x0, y1)), ((1.0, 0.0), (x1, y0), (x1, y1)),
                             ((0.0, -1.0), (x0, y0), (x1, y0)), ((0.0, 1.0), (x0, y1), (x1, y1))):
            fx = min(max(p[0], min(a[0], c[0])), max(a[0], c[0]))
            fy = min(max(p[1], min(a[1], c[1])), max(a[1], c[1]))
            faces.append((dist_point_segment(p, a, c), normal, (fx, fy)))
    if not faces:
        return None, None
    faces.sort(key=lambda f: f[0])
    for _, normal, foot in faces:
        if not in_footprint((foot[0] + normal[0] * distance, foot[1] + normal[1] * distance), footprints):
            return normal, foot
    return faces[0][1], faces[0][2]


def facade_standoff(p: Sequence[float], footprints: Sequence[Sequence[float]], distance: float) -> tuple:
    """((x, y, z), yaw) `distance` m out from the facade of p (open_face of the buildings rising to p's
    height), level with p, facing the wall. Out from the wall's known plane, not from p: a fire estimate lies
    in the wall or in front of it by the GNSS error of the poses that placed it (realistic seed 115: a
    standoff taken from an estimate 0.6 m inside facade A put a UAV into it). The agents' standoffs and the
    central unit's viewpoints are this one rule."""
    normal, foot = open_face(p, standing_at(p, footprints), distance)
    if normal is None:
        raise ValueError('no building')
    pos = (foot[0] + normal[0] * distance, foot[1] + normal[1] * distance, p[2])
    return pos, math.atan2(-normal[1], -normal[0])


def in_footprint(p: Sequence[float], footprints: Sequence[Sequence[float]], margin: float = 0.0) -> bool:
    """True when p (xy) is inside a building footprint grown by margin (shrunk when margin < 0)."""
    return any(b[0] - margin <= p[0] <= b[2] + margin and b[1] - margin <= p[1] <= b[3] + margin
               for b in footprints)


def footprint_distance(p: Sequence[float], footprints: Sequence[Sequence[float]]) -> float:
    """Horizontal distance from p (xy) to the nearest building footprint: 0 inside one, inf without buildings."""
    return 0.0 if in_footprint(p, footprints) else nearest_face(p, footprints)[1]


# How far a fire estimate may lie off its wall and still be that wall's facade fire: robots place fires with
# standard GNSS (errors of about a metre, ual_sim README "Uncertainty"), so a facade fire seen from a pose
# off towards the building lands inside the footprint, one seen from a pose off the other way lands out in
# the open. Indoor holders are metres inside the outer walls and ground fires far from every wall.
INDOOR_DEPTH = 1.5      # m inside a footprint before a fire counts as indoors
GROUND_DISTANCE = 2.0   # m from every wall before a low fire counts as a ground fire
# Facade fires burn only in the facade holders, whose places a team knows before the trial. A fire estimated
# inside a building less than INDOOR_DEPTH from a wall, but farther than this from every facade holder, is an
# indoor fire near that wall (the west indoor holders are 1.8 m inside facade A's side wall, which has no
# holder): its estimate moved a few decimetres outwards under GNSS error must not turn it into a facade fire
# that no search looks for. A facade fire's estimate lies within about a metre and a half of its holder.
FACADE_HOLDER_REACH = 3.0   # m (3D) from a facade holder within which a fire may be that holder's


def classify_fire(position: Sequence[float], footprints: Sequence[Sequence[float]],
                  facade_holders: Sequence[Sequence[float]] = ()) -> int:
    """Object SUBTYPE_* of a fire at position, from where it is.

    Rules: more than INDOOR_DEPTH inside a footprint, under its roof -> INDOOR; lower than 1.5 m and more
    than GROUND_DISTANCE from every wall rising to that height -> GROUND; else (on or near a wall) -> FACADE,
    except, when the facade holders are given, a fire inside a footprint under its roof and farther than
    FACADE_HOLDER_REACH from every holder -> INDOOR (no facade fire can burn there).
    """
    under = standing_at(position, footprints, 0.0)   # nothing is indoors above a roof
    if in_footprint(position, under, margin=-INDOOR_DEPTH):
        return M.SUBTYPE_INDOOR
    _, d = nearest_face(position, under)
    if position[2] < 1.5 and d > GROUND_DISTANCE:
        return M.SUBTYPE_GROUND
    if facade_holders and no_facade_fire_at(position, footprints, facade_holders):
        return M.SUBTYPE_INDOOR
    return M.SUBTYPE_FACADE


def no_facade_fire_at(position: Sequence[float], footprints: Sequence[Sequence[float]],
                      facade_holders: Sequence[Sequence[float]]) -> bool:
    """True where no facade fire can be: inside a footprint under its roof, farther than FACADE_HOLDER_REACH
    from every facade holder."""
    return in_footprint(position, standing_at(position, footprints, 0.0)) and all(
        math.dist(position[:3], h[:3]) > FACADE_HOLDER_REACH for h in facade_holders)
