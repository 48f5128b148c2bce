"""The middle-of-three choice on (x, y, z, r) circles in the optical frame."""
import math

from circle_detector.hole_choice import choose_middle_hole, triple_score


def row(n=3, x0=-0.55, gap=0.55, y=0.1, z=3.0, r=0.12, yaw=0.0):
    """n circles in a horizontal row on a facade turned by `yaw` (rad)."""
    out = []
    for i in range(n):
        a = x0 + i * gap
        out.append((a * math.cos(yaw), y, z - a * math.sin(yaw), r))
    return out


def test_middle_of_three_is_chosen_whatever_the_order():
    c = row()
    assert choose_middle_hole(c) == 1
    shuffled = [c[2], c[0], c[1]]
    assert choose_middle_hole(shuffled) == 2


def test_fewer_than_three_gives_none():
    assert choose_middle_hole([]) is None
    assert choose_middle_hole(row(2)) is None


def test_facade_at_40_degrees():
    assert choose_middle_hole(row(yaw=math.radians(40))) == 1
    assert choose_middle_hole(row(yaw=math.radians(-40))) == 1


def test_spurious_circle_does_not_change_the_choice():
    c = row() + [(0.9, -1.0, 3.2, 0.3)]
    assert choose_middle_hole(c) == 1
    c = [(0.05, 0.8, 3.0, 0.06)] + row()  # a small round thing below the holder
    assert choose_middle_hole(c) == 2


def test_not_a_holder():
    # vertical column
    assert triple_score([(0.1, -0.5, 3, 0.12), (0.1, 0.0, 3, 0.12), (0.1, 0.5, 3, 0.12)]) is None
    # very different radii
    assert triple_score([(-0.5, 0, 3, 0.05), (0, 0, 3, 0.3), (0.5, 0, 3, 0.12)]) is None
    # uneven spacing
    assert triple_score([(-0.5, 0, 3, 0.12), (0.4, 0, 3, 0.12), (0.5, 0, 3, 0.12)]) is None
    # far apart for their size
    assert triple_score([(-3, 0, 3, 0.12), (0, 0, 3, 0.12), (3, 0, 3, 0.12)]) is None


def test_two_holders_best_aligned_wins():
    good = row(x0=-0.55)
    bad = [(1.2, 0.3, 3.0, 0.12), (1.8, 0.0, 3.0, 0.12), (2.4, 0.45, 3.0, 0.12)]
    assert choose_middle_hole(bad + good) == 4


def test_openings_are_the_stronger_evidence():
    """The depth seen through a circle (opening, m) decides where the triple cannot or is wrong."""
    from circle_detector.hole_choice import choose_hole
    nan = float("nan")
    c = row()
    assert choose_hole(c) == 1 and choose_hole(c, [nan] * 3) == 1           # no depth: the middle
    assert choose_hole(c, [0.0, 0.3, 0.0]) == 1
    assert choose_hole(c, [0.3, 0.0, 0.0]) == 0                              # middle painted: the opening
    assert choose_hole(c, [0.3, 0.0, 0.3]) is None                           # ambiguous: no choice
    two = row(2)                                                             # corner holder: one decoy hidden
    assert choose_hole(two) is None and choose_hole(two, [nan, nan]) is None
    assert choose_hole(two, [0.0, 0.28]) == 1 and choose_hole(two, [0.29, 0.02]) == 0
    assert choose_hole(two, [0.05, 0.02]) is None                            # both painted
    try:
        choose_hole(c, [0.0])
    except ValueError:
        pass
    else:
        raise AssertionError("mismatched openings accepted")
