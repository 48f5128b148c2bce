"""The consecutive-frame filter and its false-negative tolerance."""
from fire_detector.frame_filter import FrameFilter


def feed(f, pattern):
    return [f.update(c == "H") for c in pattern]


def test_needs_more_than_n_consecutive_hot_frames():
    f = FrameFilter(15, 0)
    out = feed(f, "H" * 16)
    assert out[:15] == [False] * 15 and out[15] is True and f.confirmed


def test_a_cold_frame_resets_before_confirmation():
    f = FrameFilter(15, 3)
    out = feed(f, "H" * 10 + "C" + "H" * 15)
    assert not any(out)
    assert f.update(True)


def test_tolerance_keeps_a_confirmed_fire():
    f = FrameFilter(3, 2)
    out = feed(f, "HHHH" + "CC" + "H")
    assert out == [False, False, False, True, False, False, True]
    assert f.confirmed


def test_tolerance_exceeded_resets():
    f = FrameFilter(3, 2)
    feed(f, "HHHH" + "CCC")
    assert not f.confirmed
    assert f.update(True) is False


def test_zero_filter_confirms_first_hot_frame():
    f = FrameFilter(0, 0)
    assert f.update(True)
