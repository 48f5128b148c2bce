"""refinement.OutlineRefinement's applied correction around the loss of the fix (no ROS, no scans: the
fitted correction set by hand)."""
from types import SimpleNamespace

import pytest

from indoor_localization.anchor import Anchor
from indoor_localization.outline import IDENTITY
from indoor_localization.refinement import OutlineRefinement
from mbzirc_arena.c3 import ARENA

FITTED = Anchor(0.0, 0.62, 0.16)          # the correction a direction observed in the window's wall gives


def core_lost_at(lost_at):
    return SimpleNamespace(frame_changes=0, anchor=Anchor(0.0, 0.0, 0.0), gnss_valid=False, lost_at=lost_at,
                           correction=IDENTITY)


def applied_after(lost_at, t, crossing_at_once=1.0):
    ref = OutlineRefinement(ARENA, crossing_at_once=crossing_at_once)
    core = core_lost_at(lost_at)
    ref.update(core, t - 0.1, (18.0, 7.0, 0.0), 7.5)         # the smoother's clock starts
    ref.refiner.correction = SimpleNamespace(transform=FITTED)
    ref.update(core, t, (18.0, 7.0, 0.0), 7.5)
    return core.correction


def test_realistic_plan_b_101_a_correction_found_in_the_windows_wall_applies_at_once():
    """c3_floor_plan_b seed 101 (realistic): both of UAV 2's flights in, the direction along the facade was
    observed 0.1-0.6 s after the fix was lost (the inner faces through the window), and the correction
    followed at ~correction_rate: the first second indoors 0.51 and 0.64 m off. Within crossing_at_once s
    of the loss it applies at once; later, deep inside, at the rate (a robot flies on that pose)."""
    assert applied_after(lost_at=651.9, t=652.0).tx == pytest.approx(0.62)
    later = applied_after(lost_at=651.9, t=660.0)
    assert 0.0 < later.tx < 0.2, later                            # 0.1 s at 1 m/s
    assert applied_after(lost_at=651.9, t=652.0, crossing_at_once=0.0).tx < 0.2
