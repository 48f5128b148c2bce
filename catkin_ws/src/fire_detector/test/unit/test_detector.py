"""The whole detector on synthetic frames of the synthetic world (scenes, filter, placement, errors)."""
import math

import numpy as np
import pytest

from fire_detector import constants as C
import synthetic_thermal as S
from fire_detector.detector import DetectorConfig, FireDetector
from fire_detector.geometry import front_laser_range


def run(scene_name, n=25, seed=1, **cfg):
    scene = S.NAMED_SCENES[scene_name]
    mode = "FORWARD" if scene.direction == C.CAMERA_DIRECTION_FORWARD else "DOWNWARD"
    det = FireDetector(DetectorConfig(camera_config=mode, **cfg))
    rng = np.random.default_rng(seed)
    fires = []
    for s, frame in S.sequence(scene, rng, n):
        ranges, amin, inc = S.render_scan(s, rng)
        lr = front_laser_range(ranges, amin, inc, S.LASER_RANGE_MIN, S.LASER_RANGE_MAX, 5.0)
        r = det.process(frame.ravel(), s.uav_xyz, s.uav_yaw, lr)
        if r.fire:
            fires.append((r.fire, s))
    return det, fires


def test_facade_fire_is_confirmed_after_the_filter_and_placed():
    det, fires = run("facade_fire")
    assert det.fire_detected
    assert 1 <= len(fires) <= 25 - C.DEFAULT_NUM_FRAME_FILTER
    errors = [np.linalg.norm(np.subtract(fire.position, s.source_arena())) for fire, s in fires]
    assert np.median(errors) < 0.3 and max(errors) < 1.5
    assert all(fire.depth == pytest.approx(3.0, abs=0.3) for fire, _ in fires)


def test_ground_fire_downward():
    det, fires = run("ground_fire")
    assert fires and det.fire_detected
    # a glitching hot pixel is a contour of its own and pulls the centroid of centroids (the original
    # algorithm) away from the fire for that frame: most frames are accurate, none is absurd
    errors = [np.linalg.norm(np.subtract(fire.position, s.source_arena())) for fire, s in fires]
    assert np.median(errors) < 0.3 and max(errors) < 1.5
    assert all(fire.depth == pytest.approx(4.0) for fire, _ in fires)


@pytest.mark.parametrize("name", ["inactive_holder", "hot_wall"])
def test_no_fire_scenes(name):
    det, fires = run(name, n=40)
    assert not fires and not det.fire_detected


def test_hot_wall_fools_the_original_threshold_alone():
    """Without the peak gate (original behaviour) the sun-heated wall is a persistent false positive."""
    det, fires = run("hot_wall", n=40, min_fire_temperature=0.0)
    assert fires


def test_no_laser_or_far_laser_gives_no_position_but_checkfire_says_yes():
    det = FireDetector(DetectorConfig(num_frame_filter=0))
    frame = np.full(1024, 25.0)
    frame[500] = 120.0
    r = det.process(frame, (0, 0, 5), 0.0, None)
    assert r.confirmed and r.fire is None and "laser" in r.reason
    r = det.process(frame, (0, 0, 5), 0.0, 8.0)
    assert r.fire is None and det.fire_detected
    r = det.process(frame, (0, 0, 5), 0.0, 7.0)
    assert r.fire is not None and r.fire.depth == 7.0
    r = det.process(frame, None, None, 7.0)
    assert r.fire is None and "pose" in r.reason


def test_bad_config_and_bad_frames_raise():
    with pytest.raises(ValueError):
        DetectorConfig(camera_config="SIDEWAYS")
    det = FireDetector(DetectorConfig())
    with pytest.raises(ValueError):
        det.process([1.0] * 3, (0, 0, 0), 0.0, 3.0)


def test_random_scenes_recall_and_no_false_positive_small_sample():
    rng = np.random.default_rng(7)
    tp = fp = pos = 0
    for i in range(24):
        kind = S.SCENE_KINDS[i % 4]
        scene = S.random_scene(rng, C.CAMERA_DIRECTION_FORWARD, rng.uniform(1.0, 4.0), kind)
        det = FireDetector(DetectorConfig())
        hit = None
        for s, frame in S.sequence(scene, rng, 20):
            ranges, amin, inc = S.render_scan(s, rng)
            lr = front_laser_range(ranges, amin, inc, 0.15, 25.0, 5.0)
            r = det.process(frame.ravel(), s.uav_xyz, s.uav_yaw, lr)
            hit = hit or (r.fire and (r.fire, s))
        truth = S.scene_truth(scene)
        pos += truth is not None
        if hit:
            ok = truth is not None and np.linalg.norm(np.subtract(hit[0].position, hit[1].source_arena())) < 1.0
            tp += ok
            fp += not ok
    assert pos == 6 and tp == pos and fp == 0
