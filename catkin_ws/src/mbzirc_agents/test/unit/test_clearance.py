"""The clearance guard's rules (clearance.py), without an agent: which surfaces the arena plan puts under a
point, the vertical GNSS error from the altimeter, the bounds on set-points and velocities, the fallback."""
import math

import pytest

from mbzirc_agents import constants as C
from mbzirc_agents.clearance import ClearanceConfig, ClearanceGuard, surfaces_at

A4_STANDOFF = (23.7, 21.0)           # in front of facade holder A_4 (0.75 m up), outside every footprint
EXT_ROOF = (30.0, 12.0)              # over the extension's roof (4.5 m)


@pytest.fixture
def guard():
    return ClearanceGuard(ClearanceConfig(), C.BUILDINGS, C.FLOOR_HEIGHTS, 0.0)


def test_surfaces_of_the_plan():
    s = lambda x, y: surfaces_at(x, y, C.BUILDINGS, C.FLOOR_HEIGHTS, 0.0, 1.0)  # noqa: E731
    assert s(0.0, 0.0) == [0.0]
    assert s(*A4_STANDOFF) == [0.0]
    assert s(*EXT_ROOF) == [0.0, 4.5]
    assert s(17.0, 12.0) == [0.0, 5.0, 10.0, 18.0]        # inside the tower: its storeys and its roof
    assert s(24.0, 20.2) == [0.0, 4.5, 18.0]             # 0.7 m off both roofs: maybe over them, no storey


def test_the_altimeter_gives_the_vertical_gnss_error(guard):
    guard.on_reading(0.75, 10.0, (0.0, 0.0, 1.25))        # the fix reads 0.5 m high
    assert guard.error == pytest.approx(0.5)
    assert guard.fresh(11.4) and not guard.fresh(11.6)
    g2 = ClearanceGuard(ClearanceConfig(), C.BUILDINGS, C.FLOOR_HEIGHTS, 0.0)
    g2.on_reading(1.5, 10.0, (*EXT_ROOF, 5.7))            # over the roof: 1.5 m above 4.5 m, fix 0.3 low
    assert g2.error == pytest.approx(-0.3)
    g3 = ClearanceGuard(ClearanceConfig(), C.BUILDINGS, C.FLOOR_HEIGHTS, 0.0)
    g3.on_reading(2.5, 10.0, (20.0, 19.9, 12.6))           # in a floor-2 window, the fix 0.4 m outside
    assert g3.error == pytest.approx(0.1)                  # the storey's floor explains it (not the ground)
    assert g3.surfaces(20.0, 19.9) == [0.0, 18.0]          # but no floor is under a UAV outside for the bounds


def test_the_estimate_is_smoothed_and_restarts_after_a_gap(guard):
    guard.on_reading(1.0, 10.0, (0.0, 0.0, 1.0))
    guard.on_reading(1.0, 10.05, (0.0, 0.0, 1.2))         # one noisy reading: the estimate moves a little
    assert 0.0 < guard.error < 0.1
    guard.on_reading(1.0, 20.0, (0.0, 0.0, 1.4))          # 10 s later: taken as it is
    assert guard.error == pytest.approx(0.4)


def test_set_points_keep_the_clearance_above_the_true_surface(guard):
    guard.on_reading(0.75, 10.0, (*A4_STANDOFF, 1.55))    # e = +0.8: a set-point at 0.75 is 0.05 m underground
    z = guard.safe_set_point_z(*A4_STANDOFF, 0.75, 10.1)
    assert z - guard.error == pytest.approx(0.5 + 0.2)     # true height: the clearance and the hysteresis
    assert guard.safe_set_point_z(*A4_STANDOFF, 3.0, 10.1) == 3.0     # high enough: unchanged
    guard.on_reading(1.5, 13.0, (*EXT_ROOF, 6.0))          # over the roof, e = 0
    assert guard.safe_set_point_z(*EXT_ROOF, 4.7, 13.05) == pytest.approx(4.5 + 0.7)
    assert guard.safe_set_point_z(*EXT_ROOF, 6.0, 13.05) == 6.0


def test_without_a_fresh_reading_the_bound_takes_the_fallback_margin(guard):
    assert 'never' in guard.problem(5.0)
    assert guard.safe_set_point_z(*A4_STANDOFF, 0.75, 5.0) == pytest.approx(0.5 + 1.0)
    guard.on_reading(0.75, 10.0, (*A4_STANDOFF, 0.75))
    guard.on_reading(math.nan, 10.5, (*A4_STANDOFF, 0.75))
    assert guard.problem(11.4) == ''                       # one NaN: still fresh
    assert guard.problem(12.0).startswith('no valid altimeter reading for 2.0 s')
    assert 'NaN' in guard.problem(12.0)
    assert guard.safe_set_point_z(*A4_STANDOFF, 0.75, 12.0) == pytest.approx(1.5)
    guard.on_reading(0.75, 12.5, (*A4_STANDOFF, 0.75))      # valid again, then silent
    assert 'no reading arrived' in guard.problem(14.5)        # not the NaN of before


def test_a_reading_no_surface_explains_is_not_believed(guard):
    guard.on_reading(0.2, 10.0, (0.0, 0.0, 6.0))          # 5.8 m of error? an object under the UAV
    assert guard.error is None and 'fits no surface' in guard.problem(11.6)
    guard.on_reading(6.1, 20.0, (0.0, 0.0, 6.0))          # e = -0.1
    guard.on_reading(5.0, 20.05, (0.0, 0.0, 6.0))         # a window sill 1.1 m up passes under the UAV
    assert guard.error == pytest.approx(-0.1) and guard.fresh(20.1)
    assert 'jumps' in guard.last_problem
    guard.on_reading(5.0, 21.6, (0.0, 0.0, 6.0))          # persists past max_age: believed (stale before)
    assert guard.error == pytest.approx(1.0)


def test_a_jump_of_the_fix_is_believed_at_once(guard):
    """A GNSS re-fix moves the reported height by a metre; the altimeter did not move: the new error."""
    guard.on_reading(2.0, 10.0, (0.0, 0.0, 2.1))
    guard.on_reading(2.0, 10.05, (0.0, 0.0, 3.1))
    assert guard.error == pytest.approx(1.1) and guard.fresh(10.1)


@pytest.mark.parametrize('height, vz, expected', [
    (2.0, -0.5, -0.5),              # far above the bound: as commanded
    (1.0, -0.5, -0.3),              # 0.3 m above the bound (0.5 + 0.2): at most 0.3 m/s down (in 1 s)
    (0.7, -0.5, 0.0),               # at the bound: no lower
    (0.4, 0.0, 0.3),                # below it: climb back
    (0.4, 0.8, 0.8),                # climbing faster anyway
])
def test_velocities_never_take_the_height_below_the_bound(guard, height, vz, expected):
    guard.on_reading(height, 10.0, (0.0, 0.0, height + 0.4))
    assert guard.safe_vz(vz, (0.0, 0.0, height + 0.4), 10.05) == pytest.approx(expected)


def test_velocity_fallback_uses_the_gnss_height_with_the_margin(guard):
    assert guard.safe_vz(-0.5, (0.0, 0.0, 1.5), 10.0) == pytest.approx(0.0)        # 1.5 = 0.5 + 1.0
    assert guard.safe_vz(-0.5, (0.0, 0.0, 1.2), 10.0) == pytest.approx(0.3)


FLOOR1_WINDOW = (15.5, 6.8)          # in the tower's floor-1 window on its y = 6.7 facade (storey floor 5.0 in the plan; sill higher)


def _hold_over_a_sill(guard, held: bool):
    """A UAV with its fix 0.3 m high, over the ground before a floor-1 window, then 4 s in the window over a
    sill 1.5 m above the storey's floor (a height the plan does not have), the altimeter at 10 Hz."""
    true_z, e_true, sill = 7.5, 0.3, 6.5
    t = 10.0
    for _ in range(10):                                   # outside: the ground below
        guard.on_reading(true_z, t, (FLOOR1_WINDOW[0], 4.0, true_z + e_true))
        t += 0.1
    assert guard.error == pytest.approx(e_true)
    if held:
        assert guard.hold(t)
    for _ in range(40):                                   # in the window: the sill below
        guard.on_reading(true_z - sill, t, (*FLOOR1_WINDOW, true_z + e_true))
        t += 0.1
    return t, e_true


def test_a_sill_read_after_a_gap_is_taken_for_the_floor_without_a_hold(guard):
    t, e_true = _hold_over_a_sill(guard, held=False)
    assert guard.error == pytest.approx(e_true + 1.5)    # the defect the hold exists for: 1.5 m off


def test_passing_an_opening_the_estimate_is_held_not_taken_from_the_sill(guard):
    t, e_true = _hold_over_a_sill(guard, held=True)
    assert guard.fresh(t) and guard.error == pytest.approx(e_true)
    guard.release()
    guard.on_reading(7.5 - 5.0, t + 0.1, (15.5, 9.0, 7.5 + e_true))   # in the room: the storey's floor
    assert guard.error == pytest.approx(e_true)


def test_a_held_estimate_goes_stale_after_hold_max_age_readings_wait_for_the_release(guard):
    guard.on_reading(0.75, 10.0, (0.0, 0.0, 1.25))
    assert guard.hold(10.5)
    assert guard.fresh(10.5 + guard.cfg.hold_max_age) and not guard.fresh(10.6 + guard.cfg.hold_max_age)
    guard.on_reading(0.75, 19.0, (0.0, 0.0, 1.25))         # still in the opening: ignored, fallback
    assert not guard.fresh(19.1)
    g2 = ClearanceGuard(ClearanceConfig(), C.BUILDINGS, C.FLOOR_HEIGHTS, 0.0)
    g2.on_reading(0.75, 10.0, (0.0, 0.0, 1.25))
    assert not g2.hold(12.0) and not g2.fresh(12.0)
    g2.on_reading(0.75, 12.1, (0.0, 0.0, 1.25))            # not believed before the release
    assert not g2.fresh(12.2)
    g2.release()
    g2.on_reading(0.75, 12.3, (0.0, 0.0, 1.35))
    assert g2.fresh(12.4) and g2.error == pytest.approx(0.6)


def test_a_hold_tracked_by_the_vertical_velocity_follows_the_gnss_error_and_the_climb(guard):
    """Realistic seeds 101, 106: UAVs 5-10 s in a window's wall hit its lintel or sill, 0.5-0.8 m off the height
    they had centred on; the held estimate of the vertical GNSS error stood still while the error wandered
    0.3-0.5 m, and went stale after hold_max_age. Tracked by the UAV's vertical velocity from the hold's start:
    the error falls 0.6 m in 6 s while the UAV truly sinks 0.3 m (vz -0.05 m/s, 30 Hz): the true height and
    the error are both right, still fresh after hold_max_age, the GNSS noise of each fix not in the height."""
    guard.on_reading(7.5, 10.0, (FLOOR1_WINDOW[0], 4.0, 7.8))           # e = +0.3, true z 7.5
    assert guard.hold(10.0, 7.8)
    t, true_z = 10.0, 7.5
    noise = [0.05, -0.05, 0.0]
    for k in range(1, 12 * 30 + 1):                                    # 12 s at 30 Hz
        t = 10.0 + k / 30.0
        vz = -0.05 if t <= 16.0 else 0.0
        true_z += vz / 30.0
        e = 0.3 - 0.1 * min(t - 10.0, 6.0)
        guard.on_velocity(vz, t, true_z + e + noise[k % 3])
    assert guard.true_z(99.0, t) == pytest.approx(7.2, abs=1e-6)        # 7.5 - 0.3: no GNSS in it
    assert guard.fresh(t) and t > 10.0 + guard.cfg.hold_max_age
    assert guard.error == pytest.approx(-0.3, abs=0.06)
    assert guard.tracking(t)


def test_a_tracked_hold_without_velocities_falls_back_to_the_held_estimates_age(guard):
    """No vertical velocity for longer than max_age: the climb meanwhile is unknown, the tracking ends and the
    held estimate counts only until hold_max_age after the hold's start (as without a velocity at all)."""
    guard.on_reading(7.5, 10.0, (FLOOR1_WINDOW[0], 4.0, 7.8))
    assert guard.hold(10.0, 7.8)
    guard.on_velocity(0.0, 10.1, 7.8)
    assert not guard.fresh(10.1 + guard.cfg.max_age + 0.05)           # velocities stopped: not fresh
    guard.on_velocity(0.0, 12.0, 7.8)                                   # after a gap: no more tracking
    assert not guard.tracking(12.0) and guard.fresh(12.0)
    assert guard.true_z(7.8, 12.0) == pytest.approx(7.5)              # the GNSS height less the held e
    assert not guard.fresh(10.1 + guard.cfg.hold_max_age)
    guard.release()
    assert not guard.tracking(12.0)
