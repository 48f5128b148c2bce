"""The opening finder (openings.find_opening) on scans recorded in ual_sim runs: a water UAV approaching
and leaving windows of the tower, the UGV at its door (data/window_scans.npz, made by
data/make_window_scans.py from the on-demand rostests' bags: the simulator's laser with its realistic noise
and dropouts, the robot moving and swaying, other walls in view; the truth from /sim/robots and the world
file, test-only; the width asked is the world's, which the arena model gives for the default world).

Every recorded opening is found where it is, as wide as it is, approaching from outside and leaving from
inside. From inside, near a room's corner (the UGV held just inside its door by the room's east wall, a UAV
1.4 m aside of its window), the finder had fitted its wall line to the side walls' returns at the sector's
ends as well and found none (17 of 24 inside views): the wall is now one stretch of returns."""
import os

import numpy as np
import pytest

from mbzirc_agents.openings import find_opening

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'data', 'window_scans.npz')
LATERAL_TOL = 0.15      # m: the passage centres the frame on it (a UAV has ~0.4 m each side in a 2 m window)
WIDTH_TOL = 0.3         # m: the passage refuses an opening sensed narrower than its frame needs


def recorded():
    d = np.load(DATA)
    return [dict((k, d[k][i]) for k in d.files) for i in range(len(d['lateral']))]


SCANS = recorded()
OUTSIDE = [i for i, s in enumerate(SCANS) if not s['inside']]
INSIDE = [i for i, s in enumerate(SCANS) if s['inside']]


def found_where_it_is(s):
    """(found within the tolerances, what was seen)."""
    seen = find_opening(s['ranges'].astype(float), float(s['angle_min']), float(s['angle_increment']),
                        float(s['width']), expected_lateral=0.0, range_min=float(s['range_min']),
                        range_max=float(s['range_max']))
    ok = (seen is not None and abs(seen.lateral - s['lateral']) <= LATERAL_TOL
          and abs(seen.width - s['width']) <= WIDTH_TOL)
    return ok, seen


def test_the_recording_holds_windows_and_the_door_from_both_sides():
    sources = {str(s['source']) for s in SCANS}
    assert len(sources) >= 2 and len(OUTSIDE) >= 20 and len(INSIDE) >= 20, (sources, len(OUTSIDE), len(INSIDE))
    assert any(abs(SCANS[i]['width'] - 2.5) < 0.01 for i in OUTSIDE)        # the door
    assert any(abs(SCANS[i]['width'] - 2.0) < 0.01 for i in OUTSIDE)        # windows


@pytest.mark.parametrize('i', OUTSIDE)
def test_approaching_each_recorded_opening_is_found_where_it_is(i):
    s = SCANS[i]
    ok, seen = found_where_it_is(s)
    assert ok, (str(s['source']), float(s['lateral']), float(s['distance']), float(s['width']), seen)


@pytest.mark.parametrize('i', INSIDE)
def test_leaving_each_recorded_opening_is_found_where_it_is_even_near_a_rooms_corner(i):
    s = SCANS[i]
    ok, seen = found_where_it_is(s)
    assert ok, (str(s['source']), float(s['lateral']), float(s['distance']), float(s['width']), seen)
