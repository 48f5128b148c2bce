"""The Hough pipeline on synthetic RGB-D facades, and its input checks."""
import math

import numpy as np
import pytest

import synthetic_rgbd as S
from circle_detector.hole_choice import choose_middle_hole
from circle_detector.hough import HoughParams, Intrinsics, depth_to_metres, detect_circles
from circle_detector.rectify import fit_plane

TUNED = dict(use_gaussian_blur=True, gaussian_blur_kernel_size=5, min_dist_between_circle_center=30,
             accumulator_threshold=24, downscale=2, rectify=True)


def detect(scene, seed=0, **kw):
    rng = np.random.default_rng(seed)
    colour, depth = S.render(scene, rng)
    return detect_circles(colour, depth_to_metres(depth, "16UC1"), S.DEFAULT_K, HoughParams(**{**TUNED, **kw}))


def test_named_holder_three_circles_and_middle_is_the_hole():
    scene = S.NAMED_SCENES["facade_holder"]
    circles = detect(scene)
    assert len(circles) == 3
    i = choose_middle_hole([(c.x, c.y, c.z, c.radius_m) for c in circles])
    assert i is not None
    hole = circles[i]
    assert np.linalg.norm(np.subtract((hole.x, hole.y, hole.z), scene.hole_cam)) < 0.05
    assert hole.radius_m == pytest.approx(scene.radius, rel=0.2)


@pytest.mark.parametrize("rectify", [True, False])
def test_depth_through_the_hole_tells_it_from_the_decoys(rectify):
    """opening_m: the middle of the real hole lies ~0.3 m (the container) behind its rim, a decoy's on it."""
    scene = S.NAMED_SCENES["facade_holder"]
    circles = detect(scene, rectify=rectify)
    assert len(circles) == 3
    hole = min(circles, key=lambda c: np.linalg.norm(np.subtract((c.x, c.y, c.z), scene.hole_cam)))
    assert hole.opening_m == pytest.approx(S.HOLE_DEPTH, abs=0.1)
    for c in circles:
        if c is not hole:
            assert abs(c.opening_m) < 0.05


def test_plain_wall_has_no_circle():
    assert detect(S.NAMED_SCENES["plain_wall"]) == []


@pytest.mark.parametrize("yaw_deg", [-40, 40])
def test_oblique_facade_needs_rectification(yaw_deg):
    scene = S.FacadeScene((0.0, 0.0, 3.5), math.radians(yaw_deg), 0.0, 0.15, 0.7, 170.0, 40.0)
    circles = detect(scene)
    i = choose_middle_hole([(c.x, c.y, c.z, c.radius_m) for c in circles])
    assert i is not None
    assert np.linalg.norm(np.subtract((circles[i].x, circles[i].y, circles[i].z), scene.hole_cam)) < 0.08


def test_circles_beyond_max_depth_or_radius_are_dropped():
    scene = S.NAMED_SCENES["facade_holder"]
    assert detect(scene, max_depth_th=2.0) == []
    assert detect(scene, max_radius_meters=0.08) == []
    assert len(detect(scene, rectify=False, downscale=1)) >= 1


def test_size_mismatch_and_bad_encoding_raise():
    K = S.DEFAULT_K
    with pytest.raises(ValueError):
        detect_circles(np.zeros((480, 640, 3), np.uint8), np.zeros((240, 320), np.float32), K, HoughParams())
    with pytest.raises(ValueError):
        detect_circles(np.zeros((480, 640), np.uint8), np.zeros((480, 640), np.float32), K, HoughParams())
    with pytest.raises(ValueError):
        depth_to_metres(np.zeros((4, 4), np.uint8), "mono8")


def test_depth_conversion():
    d = depth_to_metres(np.array([[0, 1500]], np.uint16), "16UC1")
    assert np.isnan(d[0, 0]) and d[0, 1] == pytest.approx(1.5)
    f = depth_to_metres(np.array([[np.nan, -1.0, 2.0]], np.float32), "32FC1")
    assert np.isnan(f[0, 0]) and np.isnan(f[0, 1]) and f[0, 2] == 2.0


def test_no_valid_depth_gives_nothing():
    colour = np.full((480, 640, 3), 128, np.uint8)
    assert detect_circles(colour, np.full((480, 640), np.nan, np.float32), S.DEFAULT_K, HoughParams()) == []


def test_intrinsics_from_k():
    K = Intrinsics.from_k([462.1, 0, 320, 0, 462.1, 240, 0, 0, 1], 640, 480)
    assert (K.fx, K.cy, K.width) == (462.1, 240.0, 640)
    with pytest.raises(ValueError):
        Intrinsics.from_k([0.0] * 9, 640, 480)


def test_plane_fit_recovers_facade_normal():
    scene = S.FacadeScene((0.0, 0.0, 3.0), math.radians(30), 0.0, 0.12, 0.55, 170.0, 40.0)
    _, depth = S.render(scene, np.random.default_rng(3))
    K = S.DEFAULT_K
    plane = fit_plane(depth_to_metres(depth, "16UC1"), K.fx, K.fy, K.cx, K.cy)
    _, _, n = scene.axes()
    assert plane is not None and abs(float(plane.normal @ n)) > math.cos(math.radians(2))
