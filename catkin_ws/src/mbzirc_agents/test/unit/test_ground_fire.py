"""extinguish_ground_fire against a fake UAL flying the agent's velocity commands and a fake downward thermal
camera: the blanket falls where the camera has the fire under the UAV, never where the estimate says.

Why: the estimate is placed on the GNSS fixes of whoever saw the fire; in the UAV's own GNSS frame it may
be most of a metre off (realistic seed 103: a blanket released beside the fire, which burned on)."""
import math

import numpy as np
import pytest
from mbzirc_comm_objs.msg import (ExtinguishGroundFireGoal, Object, ObjectDetection, ObjectDetectionList,
                                  ObjectList, TakeOffGoal)
from std_msgs.msg import Bool
from uav_abstraction_layer.srv import GoToWaypointResponse
from std_srvs.srv import TriggerResponse

from fake_backend import FakeBackend
from fake_ual import start_uav, stop_agent
from mbzirc_agents import constants as C
from mbzirc_agents.control import world_to_body

FIRE = np.array([3.0, 0.0, 0.0])            # the plate (truth)
ESTIMATE_ERROR = np.array([0.0, 0.8, 0.0])  # the track in the UAV's GNSS frame, as another robot's fix put it
VIEW = 0.3                                  # the camera sees the fire while its offset <= VIEW x the height
COVERS = 0.3                                # m: a blanket released this close to the plate's centre covers it


class DownwardCamera:
    """Detections of the fire as the fire detector sends them (~14 Hz): the body-relative offset from the
    true pose, placed in the arena with the reported (GNSS) pose; nothing while it is out of view or blind."""

    def __init__(self, sc, blind=False):
        self.sc, self.blind, self.stop = sc, blind, False
        sc.be.clock.start_thread(self._loop, name='downward camera')

    def _loop(self):
        be, ual = self.sc.be, self.sc.ual
        while not self.stop:
            with ual.lock:
                pos, yaw, reported = ual.pos.copy(), ual.yaw, ual.pos + ual.gnss_bias
            h = pos[2] - FIRE[2]
            off = FIRE[:2] - pos[:2]
            if not self.blind and h > 0.5 and np.hypot(*off) <= VIEW * h and 'sensed_objects' in be.subs:
                rel = world_to_body((off[0], off[1], -h), yaw)
                det = ObjectDetection(type=C.TYPE_FIRE)
                det.header.stamp.secs, det.header.stamp.nsecs = divmod(int(be.clock.now() * 1e9), 10 ** 9)
                det.pose.pose.position.x, det.pose.pose.position.y = reported[:2] + (FIRE - pos)[:2]
                det.relative_position.x, det.relative_position.y, det.relative_position.z = rel
                det.image_detection.camera_direction = C.CAMERA_DOWNWARD
                be.subs['sensed_objects'](ObjectDetectionList(objects=[det]))
            be.clock.sleep(0.07)


class Gust:
    """Pushes the UAV `push` m sideways once, the first time it is below `below` m: the fire leaves the
    narrow view of the low camera."""

    def __init__(self, sc, below, push):
        self.sc, self.below, self.push, self.stop, self.done = sc, below, np.asarray(push, float), False, False
        sc.be.clock.start_thread(self._loop, name='gust')

    def _loop(self):
        ual = self.sc.ual
        while not self.stop and not self.done:
            with ual.lock:
                if ual.pos[2] < self.below and ual.state == 4:
                    ual.pos = ual.pos + self.push
                    self.done = True
            self.sc.be.clock.sleep(0.02)


class Watch:
    """The UAV's true horizontal distance from `point`, every 0.1 s."""

    def __init__(self, sc, point):
        self.sc, self.point, self.stop, self.distances = sc, np.asarray(point, float), False, []
        sc.be.clock.start_thread(self._loop, name='watch')

    def _loop(self):
        while not self.stop:
            with self.sc.ual.lock:
                self.distances.append(math.hypot(*(self.sc.ual.pos[:2] - self.point[:2])))
            self.sc.be.clock.sleep(0.1)


class Scene:
    """The blanket UAV at 4 m with a blanket, one ground fire track ESTIMATE_ERROR from the plate."""

    def __init__(self, estimate_error=ESTIMATE_ERROR):
        self.be = FakeBackend()
        self.released = []              # true positions of the blanket releases
        self.statuses = []
        self.threads = ()
        self.be.handlers['actuators_system/release_blanket'] = self._release
        self.be.handlers['/set_object_status'] = lambda r: self.statuses.append(r.object_status) or type('R', (), {})()
        self.agent, self.ual = start_uav(self.be, {'payload': 'blanket', 'centering_timeout': 15.0}, speedup=1.0)
        self.ual.follow_velocity = True
        self.be.subs['actuators_system/blanket_attached'](Bool(data=True))
        s = self.be.servers['take_off_action']
        s.send(TakeOffGoal(height=4.0))
        assert s.wait(10) == 'succeeded'
        o = Object(id=5, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_GROUND, status=C.STATUS_ACTIVE, num_updates=50)
        o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = FIRE + np.asarray(estimate_error, float)
        self.be.subs['/estimated_objects'](ObjectList(objects=[o]))

    def _release(self, _req):
        with self.ual.lock:
            self.released.append(self.ual.pos.copy())
        self.be.subs['actuators_system/blanket_attached'](Bool(data=False))
        return TriggerResponse(success=True, message='')

    def extinguish(self):
        s = self.be.servers['extinguish_ground_fire_action']
        s.send(ExtinguishGroundFireGoal(fire_id=5))
        assert s.wait(60) in ('succeeded', 'aborted')
        return s

    def close(self):
        stop_agent(self.agent, self.ual, self.be, *self.threads)


@pytest.fixture
def scene():
    made = []
    yield lambda **kw: made.append(Scene(**kw)) or made[-1]
    for sc in made:
        sc.close()


def offsets(sc):
    return [math.hypot(*(p[:2] - FIRE[:2])) for p in sc.released]


def test_the_blanket_falls_where_the_camera_has_the_fire_under_the_uav(scene):
    sc = scene()
    sc.threads = (DownwardCamera(sc),)
    s = sc.extinguish()
    assert s.status == 'succeeded', s.result.message
    assert len(sc.released) == 1 and offsets(sc)[0] <= COVERS, offsets(sc)
    assert sc.released[0][2] < 2.0


def test_a_gust_at_low_height_does_not_send_the_blanket_to_the_estimate(scene):
    """Pushed 1 m off at 1.8 m, where the camera sees only 0.54 m around: out of sight, the UAV climbs back
    over where it last saw the fire, finds it again and releases over it, not over the estimate (0.8 m off,
    on the side the gust pushed it to)."""
    sc = scene()
    sc.threads = (DownwardCamera(sc), Gust(sc, below=1.8, push=(0.0, 1.0, 0.0)))
    s = sc.extinguish()
    assert sc.threads[1].done
    assert s.status == 'succeeded', s.result.message
    assert len(sc.released) == 1 and offsets(sc)[0] <= COVERS, offsets(sc)


def test_a_fire_the_camera_never_sees_gets_no_blanket(scene):
    """The estimate alone does not release the blanket: the goal fails (the central unit tries again), the
    blanket stays on for a fire the camera can see."""
    sc = scene()
    sc.threads = (DownwardCamera(sc, blind=True),)
    s = sc.extinguish()
    assert s.status == 'aborted' and 'never seen' in s.result.message, s.result.message
    assert sc.released == [] and sc.statuses == []
    assert sc.ual.min_flying_z > 3.0            # it never went down blind


def test_a_fire_out_of_the_image_over_the_estimate_is_searched_for_and_covered(scene):
    """The estimate 1.6 m off (both GNSS errors): over it, the camera at 4 m (1.2 m around) does not see the
    fire. Before: hovering over the estimate until 'never seen', blanket kept (realistic seeds). Now the
    spiral around the estimate finds it, and the blanket falls where the camera has it under the UAV."""
    sc = scene(estimate_error=(-1.1, 1.15, 0.0))
    sc.threads = (DownwardCamera(sc),)
    s = sc.extinguish()
    assert s.status == 'succeeded', s.result.message
    assert len(sc.released) == 1 and offsets(sc)[0] <= COVERS, offsets(sc)
    assert sc.statuses == [C.STATUS_EXTINGUISHED]


def test_the_search_is_bounded_and_says_why_it_gave_up(scene):
    """A fire the camera never sees (covered already): the spiral stays within its radius and the search
    height, and the goal fails naming the radius searched, blanket kept."""
    sc = scene()
    watch = Watch(sc, FIRE + ESTIMATE_ERROR)
    sc.threads = (DownwardCamera(sc, blind=True), watch)
    s = sc.extinguish()
    far = watch.distances
    radius = sc.agent.p.ground_fire_search_radius
    assert s.status == 'aborted', s.result.message
    assert f'within {radius:.1f} m of its estimate' in s.result.message, s.result.message
    assert 'covered already' in s.result.message
    assert max(far) > 1.0                       # it did search
    assert max(far) <= math.sqrt(2) * (radius + 0.3)
    assert sc.released == [] and sc.ual.min_flying_z > 3.0


def test_a_failed_climb_back_after_the_release_still_marks_the_fire_out(scene):
    """The blanket fell, then the climb back fails (the UAL ignores the go-to): the fire is covered and
    reported EXTINGUISHED all the same. Before: the status was set only after the climb, the fire stayed
    ACTIVE and the central unit sent the next blanket to it (realistic seed 108: twice 'never seen')."""
    sc = scene()
    sc.threads = (DownwardCamera(sc),)
    release = sc._release

    def release_then_stick(req):
        sc.be.handlers['ual/go_to_waypoint'] = lambda _r: GoToWaypointResponse()
        return release(req)
    sc.be.handlers['actuators_system/release_blanket'] = release_then_stick
    s = sc.extinguish()
    assert len(sc.released) == 1
    assert s.status == 'aborted' and 'climb back' in s.result.message, s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]


def test_the_spiral_covers_the_radius_without_gaps():
    from mbzirc_agents.tasks.ground import footprint_half_width, square_spiral
    half = footprint_half_width(4.0, 33.0)
    assert half == pytest.approx(4.0 * math.tan(math.radians(16.5)))
    for radius in (0.5, 2.0, 3.5):
        pts = square_spiral((10.0, -3.0), half, radius)
        assert np.allclose(pts[0], (10.0, -3.0))
        segs = list(zip(pts[:-1], pts[1:]))
        for ang in np.linspace(0, 2 * math.pi, 72, endpoint=False):
            for r in np.linspace(0, radius, 9):
                q = np.array([10.0 + r * math.cos(ang), -3.0 + r * math.sin(ang)])
                d = min([np.hypot(*(q - pts[0]))] + [_seg_dist(q, a, b) for a, b in segs])
                assert d <= half + 1e-9, (radius, q)


def _seg_dist(q, a, b):
    ab = b - a
    t = np.clip(np.dot(q - a, ab) / np.dot(ab, ab), 0.0, 1.0)
    return float(np.hypot(*(q - (a + t * ab))))
