"""Hot-spot finding on one 32x32 frame."""
import numpy as np
import pytest

from fire_detector.thermal import find_hot_spot, parse_temperatures


def cold(t=25.0):
    return np.full((32, 32), t)


def test_no_hot_pixel_gives_none():
    assert find_hot_spot(cold(), 37.0) is None


def test_single_blob_centroid_and_box():
    f = cold()
    f[10:14, 20:26] = 100.0  # rows 10-13, cols 20-25
    s = find_hot_spot(f, 37.0)
    assert s is not None
    assert s.u == pytest.approx(22.5, abs=0.3)
    assert s.v == pytest.approx(11.5, abs=0.3)
    assert (s.width, s.height) == (6, 4)
    assert s.max_temperature == 100.0
    assert s.num_contours == 1 and s.hot_pixels == 24


def test_centroid_is_mean_of_contour_centroids_not_pixel_weighted():
    f = cold()
    f[0:10, 0:10] = 90.0   # big blob centred at (4.5, 4.5)
    f[30, 30] = 90.0       # one pixel at (30, 30)
    s = find_hot_spot(f, 37.0)
    assert s.num_contours == 2
    assert s.u == pytest.approx((4.5 + 30) / 2, abs=0.3)
    assert s.v == pytest.approx((4.5 + 30) / 2, abs=0.3)
    assert (s.width, s.height) == (31, 31)


def test_many_contours_do_not_overflow():
    f = cold()
    f[::2, ::2] = 80.0  # 256 separate one-pixel contours
    s = find_hot_spot(f, 37.0)
    assert s.num_contours == 256
    assert s.u == pytest.approx(15.0, abs=0.01) and s.v == pytest.approx(15.0, abs=0.01)


@pytest.mark.parametrize("wall_temp", [43.0, 55.0])
def test_contrast_rejects_sun_heated_wall_and_finds_the_fire_in_it(wall_temp):
    wall = cold(wall_temp)
    assert find_hot_spot(wall, 37.0) is not None        # original behaviour: the whole wall is hot
    assert find_hot_spot(wall, 37.0, 30.0, 100.0, 0.5) is None
    wall[4:7, 24:27] = wall_temp + 35.0                  # a heater well above its wall
    s = find_hot_spot(wall, 37.0, 30.0, 100.0, 0.5)
    assert (s.u, s.v, s.hot_pixels) == (25.0, 5.0, 9)
    s0 = find_hot_spot(wall, 37.0)  # original: one contour, the whole frame, centroid in the middle
    assert s0.num_contours == 1 and abs(s0.u - 15.5) < 0.5


def test_flames_filling_the_frame_are_hot_by_saturation():
    """At 1 m the flame ring fills the view: no cooler surroundings, but hotter than any sunny wall."""
    f = cold(200.0)
    f[14:18, 14:18] = 110.0                             # the heater in the hole
    s = find_hot_spot(f, 37.0, 30.0, 100.0, 0.5)
    assert s is not None and s.hot_pixels == 1024


def test_warm_edge_against_the_sky_is_no_fire():
    """Half sky (20 degC), half a 55 degC roof edge: the wall stands 35 degC out of the median (the sky),
    but it crosses the frame while filling half of it or less: an edge band, not a flame."""
    f = cold(20.0)
    f[20:, :] = 54.0
    assert find_hot_spot(f, 37.0, 30.0, 100.0, 0.0) is not None   # contrast alone is fooled
    assert find_hot_spot(f, 37.0, 30.0, 100.0, 0.5) is None
    f[24:27, 10:13] = 140.0                                        # a fire below the edge is still seen
    s = find_hot_spot(f, 37.0, 30.0, 100.0, 0.5)
    assert s is not None and (s.u, s.v) == (11.0, 25.0)


def test_parse_rejects_wrong_length_and_all_nan():
    with pytest.raises(ValueError):
        parse_temperatures([1.0] * 1000)
    with pytest.raises(ValueError):
        parse_temperatures([float("nan")] * 1024)


def test_nan_pixels_count_as_cold():
    data = [25.0] * 1024
    data[0] = float("nan")
    data[1] = float("inf")
    data[500] = 99.0
    f = parse_temperatures(data)
    s = find_hot_spot(f, 37.0)
    assert s.hot_pixels == 1 and s.u == 500 % 32 and s.v == 500 // 32
