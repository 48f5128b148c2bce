"""Wall clearance indoors (wall_clearance.py, extinguish_indoor_fire): the watering pose stops at the
standoff the laser measures from the wall ahead, and the robot holding there backs off a wall nearer than
~min_wall_clearance. The pure geometry first, then a UAV watering a fire on a wall with its GNSS fix 0.8 m
off towards the wall (and drifting on towards it while it pumps), against the fake UAL, a ray-cast laser
(laser_world.LaserScene) and a scripted thermal camera, on the sim clock."""
import numpy as np
import pytest

from laser_world import ANGLE_MIN, INC, LaserScene, cast
from mbzirc_arena.laser import scan_points
from mbzirc_agents.wall_clearance import back_off, stop_short, wall_ahead, wall_normal_at
from test_indoor_water import FIRE, scenes  # noqa: F401 - fixture: a UAV and its fire
from test_leg_guard import Closest

WALL = (FIRE[0], -5.0, FIRE[0] + 0.2, 5.0)     # the wall the fire is on: its face at x 4.0
MIN_CLEARANCE = 1.0                             # ~min_wall_clearance's default


def seen(x, y, yaw, boxes):
    return scan_points(cast((x, y), yaw, boxes), ANGLE_MIN, INC, (x, y, 0.0, yaw), keep_near=True)


def test_the_wall_ahead_is_measured_along_the_corridor():
    assert wall_ahead(seen(2.0, 0.0, 0.0, [WALL]), (2.0, 0.0), (1.0, 0.0), 0.6, 5.0) == pytest.approx(2.0, abs=0.02)
    assert wall_ahead(seen(2.0, 0.0, 0.0, [WALL]), (2.0, 0.0), (0.0, 1.0), 0.6, 5.0) is None


def test_a_target_too_near_the_wall_ahead_is_moved_back_to_the_standoff():
    pts = seen(0.0, 0.0, 0.0, [WALL])
    short = stop_short(pts, (0.0, 0.0), (3.3, 0.0), 0.6, 1.5)
    assert short == pytest.approx((2.5, 0.0), abs=0.02)
    assert stop_short(pts, (0.0, 0.0), (2.4, 0.0), 0.6, 1.5) is None            # keeps the standoff already
    assert stop_short(pts, (0.0, 0.0), (0.0, 3.0), 0.6, 1.5) is None            # the wall is not ahead


def test_a_robot_nearer_than_the_clearance_backs_off_away_from_the_wall():
    pts = seen(3.3, 0.0, 0.0, [WALL])
    off = back_off(pts, (3.3, 0.0), 1.0, 0.2)
    assert off == pytest.approx((-0.5, 0.0), abs=0.03)
    assert back_off(seen(2.5, 0.0, 0.0, [WALL]), (2.5, 0.0), 1.0, 0.2) is None
    corner = [WALL, (-5.0, 0.8, 5.0, 1.0)]
    off = back_off(seen(3.3, 0.3, 0.0, corner), (3.3, 0.3), 1.0, 0.2)
    assert off[0] < -0.2 and off[1] < -0.2                                      # out of the corner


def test_one_stray_return_moves_nothing():
    pts = np.array([[3.5, 0.0], [9.0, 9.0]])
    assert back_off(pts, (3.3, 0.0), 1.0, 0.2) is None
    assert stop_short(pts, (0.0, 0.0), (3.3, 0.0), 0.6, 1.5) is None


def test_the_fires_wall_normal_points_to_the_robots_side_and_a_corner_has_none():
    from laser_world import cast as ray
    rng = np.random.default_rng(2)
    pts = scan_points(ray((2.9, -2.5), 1.2, [WALL], 0.01, 0.01, 0.02, rng), ANGLE_MIN, INC, (2.9, -2.5, 0.0, 1.2),
                      keep_near=True)
    n = wall_normal_at(pts, FIRE, (2.9, -2.5))                 # seen at a slant: still the wall's own normal
    assert n == pytest.approx((-1.0, 0.0), abs=0.03)
    assert wall_normal_at(pts, (FIRE[0] + 1.2, 0.0), (2.9, -2.5)) is None     # the estimate off every wall
    corner = [WALL, (-5.0, 0.0, FIRE[0] + 0.2, 0.2)]
    pts = seen(2.5, -1.0, 0.5, corner)
    assert wall_normal_at(pts, (FIRE[0], 0.0), (2.5, -1.0)) is None            # two walls: no one normal
    assert wall_normal_at(None, FIRE, (2.0, 0.0)) is None


def test_a_fire_approached_at_a_slant_is_watered_square_to_its_wall(scenes):
    """The on-demand rostest indoor_gnss_denied (3 of 3 runs): the UAV found in1_e from a pose 15-20 deg off its
    wall; the watering pose on the line from there met the wall at a grazing angle, and the whole tank went
    beside the fire while the camera saw it hot. Now the watering pose faces the fire's wall squarely."""
    sc = scenes(hot_until=2.0)
    laser = LaserScene(sc.be, sc.ual, noisy=False)
    laser.boxes = [WALL]
    sc.threads = (laser,)
    with sc.ual.lock:
        sc.ual.pos[:2] = (FIRE[0] - 1.0, FIRE[1] - 3.5)        # 16 deg off the wall, on its side
    sc.be.clock.sleep(0.5)
    s = sc.extinguish(timeout=60)
    assert s.status == 'succeeded', s.result.message
    pos = sc.ual.pos
    assert abs(pos[1] - FIRE[1]) < 0.3, f'watered from {pos[:2]}: not square to the wall (fire at {FIRE[:2]})'
    assert abs(np.remainder(sc.ual.yaw + np.pi, 2 * np.pi) - np.pi) < 0.2


class Drift:
    """Once the pump runs, the GNSS error drifts `by` m more along x over `seconds` (the UAL holds its
    set-point in the frame of the fix: the UAV's true position follows)."""

    def __init__(self, sc, by, seconds=3.0):
        self.sc, self.by, self.seconds, self.stop = sc, by, seconds, False
        self.pumping_true_x = []
        sc.be.clock.start_thread(self._loop, name='gnss drift')

    def _loop(self):
        ual, clock = self.sc.ual, self.sc.be.clock
        while not self.stop and not ual.pump:
            clock.sleep(0.02)
        b0, t0 = ual.gnss_bias.copy(), clock.now()
        while not self.stop:
            k = min(1.0, (clock.now() - t0) / self.seconds)
            with ual.lock:
                ual.gnss_bias = b0 + np.array([self.by * k, 0.0, 0.0])
                if ual.pump:
                    self.pumping_true_x.append(float(ual.pos[0]))
            clock.sleep(0.02)


@pytest.mark.parametrize('drift', [0.0, -0.8])
def test_a_uav_whose_gnss_is_off_towards_the_wall_waters_from_its_clearance(scenes, drift):
    """The fire's track on the wall (x 4.0), the UAV's fix 0.8 m short of its true x: by GNSS its watering
    pose (x 2.5) is truly 0.7 m off the wall's face; then (drift -0.8) its fix drifts 0.8 m more while it
    pumps. The laser keeps it at least ~min_wall_clearance off the wall, and the fire is put out."""
    sc = scenes(hot_until=1.5)
    sc.ual.water = 3.0                      # hot for 0.6 L, the soak after it (>= 1 s), 6 cold answers
    sc.ual.gnss_bias = np.array([-0.8, 0.0, 0.0])
    laser = LaserScene(sc.be, sc.ual, noisy=True)
    laser.boxes = [WALL]
    sc.be.clock.sleep(2.0)
    closest = Closest(sc.be, sc.ual, [WALL])
    d = Drift(sc, drift)
    sc.threads = (laser, closest, d)
    s = sc.extinguish()
    sc.be.clock.sleep(2.0)                                           # and it stays off the wall after
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert d.pumping_true_x, 'never pumped'
    assert closest.least >= MIN_CLEARANCE - 0.15, f'{closest.least:.2f} m off the wall'
    assert WALL[0] - sc.ual.pos[0] >= MIN_CLEARANCE - 0.05, sc.ual.pos
