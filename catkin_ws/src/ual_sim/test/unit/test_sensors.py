"""Sensor models: thermal (FORWARD/DOWNWARD) sees active fires and not inactive holders, cools with water;
RGB-D has the right shapes, depth of a wall in front, holes darker and deeper than the wall, decoys."""
import math

import numpy as np
import pytest

from ual_sim import constants as C
from ual_sim.fires import FireSet
from ual_sim.rgbd import RGBDCamera
from ual_sim.thermal import DOWNWARD, FORWARD, ThermalCamera, pixel_dirs, to_rgb
from ual_sim.world import load_world


@pytest.fixture(scope="module")
def world():
    return load_world()


def facing(holder, dist, offset):
    n = holder.normal
    yaw = math.atan2(-n[1], -n[0])
    pos = holder.position + n * (dist + offset[0])
    return pos, yaw


def test_pixel_dirs_orientation():
    f = pixel_dirs(FORWARD).reshape(32, 32, 3)
    assert f[0, 16, 2] > 0 and f[31, 16, 2] < 0           # row 0 = top
    assert f[16, 0, 1] > 0 and f[16, 31, 1] < 0           # column 0 = left (+y)
    d = pixel_dirs(DOWNWARD).reshape(32, 32, 3)
    assert np.all(d[..., 2] < 0) and d[0, 16, 0] > 0      # image top = UAV front


def test_thermal_sees_active_fire_not_inactive_holder(world):
    fires = FireSet(world, seed=1)
    cam = ThermalCamera(FORWARD, noise_std=0.0)
    act = next(f for f in fires.fires if f.active and f.kind == 0)
    ina = next(f for f in fires.fires if not f.active and f.kind == 0)
    img = cam.render(world, fires, *facing(act.holder, 3.0, C.THERMAL_OFFSET_FORWARD))
    assert img.shape == (32, 32)
    assert img.max() > 100.0
    r, c = np.unravel_index(img.argmax(), img.shape)
    assert abs(r - 15.5) < 4 and abs(c - 15.5) < 4       # in the middle of the image
    img2 = cam.render(world, fires, *facing(ina.holder, 3.0, C.THERMAL_OFFSET_FORWARD))
    assert img2.max() < 46.0                              # only the sun-heated wall
    assert img2.max() > 37.0                              # ... which is above the detector threshold


def test_thermal_fire_cools_with_water_and_fades_with_distance(world):
    fires = FireSet(world, seed=1)
    cam = ThermalCamera(FORWARD, noise_std=0.0)
    i = next(i for i, f in enumerate(fires.fires) if f.active and f.kind == 0)
    h = fires.fires[i].holder
    hot = cam.render(world, fires, *facing(h, 3.0, C.THERMAL_OFFSET_FORWARD)).max()
    far = cam.render(world, fires, *facing(h, 9.0, C.THERMAL_OFFSET_FORWARD)).max()
    assert far < hot
    fires.add_water(i, 0.5, 1.0)
    half = cam.render(world, fires, *facing(h, 3.0, C.THERMAL_OFFSET_FORWARD)).max()
    fires.add_water(i, 0.6, 2.0)
    out = cam.render(world, fires, *facing(h, 3.0, C.THERMAL_OFFSET_FORWARD)).max()
    assert hot > half > out and out < 46.0


def test_a_fire_is_not_seen_through_the_back_of_its_wall(world):
    """Realistic seed 107 at rtf 4: in1_e (on the east face of the 0.2 m interior wall) was seen from the
    west room within 1 m of it, through the wall, and watered from there three times; from behind its wall a
    holder shows nothing, from in front at the same distance its fire."""
    fires = FireSet(world, seed=1)
    cam = ThermalCamera(FORWARD, noise_std=0.0)
    i = next(i for i, f in enumerate(fires.fires) if f.holder.id == 'in1_e')
    fires.fires[i].active = True
    h = fires.fires[i].holder
    front, front_yaw = facing(h, 0.8, C.THERMAL_OFFSET_FORWARD)
    assert cam.render(world, fires, front, front_yaw).max() > 100.0
    behind = h.position - h.normal * (0.2 + 0.7)          # 0.7 m from the wall's back face, facing it
    assert cam.render(world, fires, behind, front_yaw + math.pi).max() < 46.0


def test_downward_thermal_sees_ground_fire_and_blanket(world):
    fires = FireSet(world, seed=1)
    cam = ThermalCamera(DOWNWARD, noise_std=0.0)
    g = next(f for f in fires.fires if f.active and f.kind == 1)
    pos = g.holder.position + np.array([0.0, 0.0, 3.0])
    img = cam.render(world, fires, pos, 0.0)
    assert img.max() > 80.0
    assert np.median(img) < 37.0                          # ground around
    g.covered = True
    assert cam.render(world, fires, pos, 0.0).max() < 46.0
    rgb = to_rgb(img)
    assert rgb.shape == (32, 32, 3) and rgb.dtype == np.uint8


def test_rgbd_shapes_and_wall_depth(world):
    fires = FireSet(world, seed=1)
    cam = RGBDCamera()
    h = next(f for f in fires.fires if f.kind == 0 and f.holder.id == "C_0").holder
    pos, yaw = facing(h, 3.0, C.CAM_OFFSET)
    bgr, depth = cam.render(world, fires, pos, yaw)
    assert bgr.shape == (480, 640, 3) and bgr.dtype == np.uint8
    assert depth.shape == (480, 640) and depth.dtype == np.uint16
    # hole in the image centre: dark and 0.3 m deeper than the wall
    assert depth[240, 320] == pytest.approx(3300, abs=20)
    assert bgr[240, 320].max() < 40
    # wall beside the decoys
    assert depth[120, 320] == pytest.approx(3000, abs=20)
    assert bgr[120, 320].min() > 100
    # decoys 0.7 m left/right: dark on the wall plane
    du = int(round(C.CAM_FX * C.DECOY_OFFSET / 3.0))
    for u in (320 - du, 320 + du):
        assert bgr[240, u].max() < 60 and depth[240, u] == pytest.approx(3000, abs=20)


def test_rgbd_window_is_open_and_sky_has_no_depth(world):
    fires = FireSet(world, seed=1)
    cam = RGBDCamera()
    # 4 m west of facade C, level with its first-floor window (y 11.5-13.5, z 6.5-8.5), facing east
    bgr, depth = cam.render(world, fires, np.array([7.25, 12.5, 7.5]), 0.0)
    # through the window: the interior wall x = 17.7, i.e. 17.7 - 7.4 = 10.3 m, beyond the 10 m limit -> 0
    assert depth[240, 320] == 0
    assert depth[240, 20] == pytest.approx(4000, abs=30)   # facade beside the window
    # looking away from everything: sky rows have no depth, ground rows do
    bgr, depth = cam.render(world, fires, np.array([-10.0, -10.0, 2.0]), math.pi + 0.5)
    assert depth[10, 320] == 0 and depth[470, 320] > 0
    info = cam.camera_info()
    assert info["K"][0] == C.CAM_FX and info["K"][2] == C.CAM_CX
