"""Laser window mean and fire placement."""
import math

import numpy as np
import pytest

from fire_detector import constants as C
from fire_detector.geometry import (downward_fire_position, forward_fire_position, front_laser_range,
                                    laser_range_along, spot_bearing, uav_heading)

INC = 2 * math.pi / 720


def scan(front_value=4.0):
    r = np.full(720, 20.0)
    r[350:371] = front_value
    return r


def test_front_window_mean():
    assert front_laser_range(scan(), -math.pi, INC, 0.15, 25.0, 5.0) == pytest.approx(4.0)


def test_invalid_beams_are_excluded_from_the_mean():
    r = scan()
    r[358] = np.nan
    r[359] = np.inf
    r[361] = 0.0       # under range_min
    r[362] = 1000.0    # over range_max
    assert front_laser_range(r, -math.pi, INC, 0.15, 25.0, 5.0) == pytest.approx(4.0)


def test_window_uses_only_beams_within_amplitude():
    r = scan()
    r[360 + 11] = 100.0  # 5.5 degrees: outside +-5 deg
    r[360 - 10] = 5.0    # 5.0 degrees: inside
    got = front_laser_range(r, -math.pi, INC, 0.15, 200.0, 5.0)
    assert got == pytest.approx((4.0 * 20 + 5.0) / 21)


def test_no_valid_beam_or_bad_increment_gives_none():
    r = np.full(720, np.nan)
    assert front_laser_range(r, -math.pi, INC, 0.15, 25.0, 5.0) is None
    assert front_laser_range(scan(), -math.pi, 0.0, 0.15, 25.0, 5.0) is None
    assert front_laser_range([], -math.pi, INC, 0.15, 25.0, 5.0) is None


def test_uav_heading_and_a_pose_without_orientation():
    assert uav_heading(0, 0, math.sin(0.4), math.cos(0.4)) == pytest.approx(0.8)
    assert uav_heading(0, 0, 0, 0) == 0.0


def test_forward_centre_pixel_is_straight_ahead():
    pos, rel = forward_fire_position((1.0, 2.0, 3.0), math.pi / 2, 4.0, C.CENTER_U, C.CENTER_V)
    assert pos == pytest.approx((1.0, 6.0, 3.0))
    assert rel == pytest.approx((4.0, 0.0, 0.0))


def test_forward_left_and_up_pixels():
    _, rel = forward_fire_position((0, 0, 0), 0.0, 4.0, C.CENTER_U - C.FOCAL_PX / 4, C.CENTER_V - C.FOCAL_PX / 8)
    assert rel == pytest.approx((4.0, 1.0, 0.5))


def test_downward_image_top_is_front_right_is_right():
    _, rel = downward_fire_position((0, 0, 5.0), 0.0, C.CENTER_U + C.FOCAL_PX / 5, C.CENTER_V - C.FOCAL_PX / 5)
    assert rel == pytest.approx((1.0, -1.0, -5.0))
    pos, _ = downward_fire_position((10.0, 10.0, 5.0), math.pi, C.CENTER_U, C.CENTER_V)
    assert pos == pytest.approx((10.0, 10.0, 0.0))


def test_range_along_a_bearing_is_the_median_of_its_window():
    r = np.full(720, 20.0)
    k = 360 + 60                                     # +30 deg (left)
    r[k - 10:k + 11] = 3.0
    r[k + 8:k + 11] = 9.0                            # a doorway's edge inside the window: not averaged in
    assert laser_range_along(r, -math.pi, INC, 0.15, 25.0, math.radians(30.0), 5.0) == pytest.approx(3.0)
    assert laser_range_along(r, -math.pi, INC, 0.15, 25.0, 0.0, 5.0) == pytest.approx(20.0)
    r[k - 10:k + 11] = np.nan
    assert laser_range_along(r, -math.pi, INC, 0.15, 25.0, math.radians(30.0), 5.0) is None
    assert laser_range_along(r, float("nan"), INC, 0.15, 25.0, 0.0, 5.0) is None


def test_spot_bearing_left_of_centre_is_positive():
    assert spot_bearing(C.CENTER_U) == pytest.approx(0.0)
    assert 15.0 < math.degrees(spot_bearing(0.0)) < C.FOV_DEG / 2.0      # the image's left edge
    assert spot_bearing(C.IMG_WIDTH - 1) < 0.0
