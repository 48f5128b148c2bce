"""search_indoor against a fake UAL and a scripted thermal camera: a blind look fails the search, and a UGV
already inside searches back the way it came."""
import numpy as np
import pytest
from mbzirc_comm_objs.msg import Object, ObjectList, SearchIndoorGoal
from mbzirc_comm_objs.srv import CheckFireResponse

from fake_backend import FakeBackend
from fake_ual import start_ugv, stop_agent
from laser_world import LaserScene
from mbzirc_agents import constants as C


@pytest.fixture
def ugv_inside():
    """The UGV at the last viewpoint of its ground-floor search path, inside the tower."""
    be = FakeBackend()
    last = C.UGV_INDOOR_PATH[-1]
    # searching back along its path (`~indoor_search plan`); exploring is test_explore_search's
    agent, ual = start_ugv(be, (last[0], last[1], 0.0), {'check_fire_time': 1.0, 'indoor_search': 'plan'})
    ual.follow_velocity = True                   # the way out through the door is laser guided
    scene = LaserScene(be, ual, laser_z=0.9)
    yield agent, ual, be
    stop_agent(agent, ual, be, scene)


def search(be, timeout=400):
    s = be.servers['search_indoor_action']
    s.send(SearchIndoorGoal(floor=0))
    return s, s.wait(timeout)


def test_a_ugv_already_inside_searches_back_the_way_it_came(ugv_inside):
    """A second search after the first found nothing (its detector had started late) failed at once three
    times: 'no path to the entrance around the building' from inside it, and the floor's fire was left."""
    agent, ual, be = ugv_inside
    be.handlers['thermal_detection/fire_detected'] = lambda r: CheckFireResponse(fire_detected=False)
    s, outcome = search(be)
    assert outcome == 'succeeded', s.result.message
    assert 'no indoor fire found' in s.result.message
    door = np.array(C.UGV_DOOR_OUTSIDE)
    assert np.linalg.norm(ual.pos[:2] - door) < 0.6        # out through the door again, the way it came in


def test_a_search_whose_thermal_camera_never_answers_fails(ugv_inside):
    """No CheckFire service (a detector started late under load): the search must not report 'no fire'."""
    agent, ual, be = ugv_inside
    agent.p.detector_wait = 2.0
    s, outcome = search(be)
    assert outcome == 'aborted' and 'does not answer' in s.result.message, s.result.message


def test_ideal_5_a_look_waits_for_a_detector_that_starts_late(ugv_inside):
    """The UGV's detector came up 25 sim-s after the UGV's first look: three searches failed at once on it,
    the UGV gave the ground floor up and its fire burned the whole trial. The look now waits for the first
    answer (~detector_wait): the search ends normally."""
    agent, ual, be = ugv_inside
    up_at = be.clock.now() + 25.0

    def late_detector(_req):
        if be.clock.now() < up_at:
            raise RuntimeError('service [/mbzirc2020_0/thermal_detection/fire_detected] unavailable')
        return CheckFireResponse(fire_detected=False)

    be.handlers['thermal_detection/fire_detected'] = late_detector
    s, outcome = search(be)
    assert outcome == 'succeeded' and 'no indoor fire found' in s.result.message, s.result.message


def test_seed_104_a_search_reports_only_fires_it_saw_hot(ugv_inside):
    """An indoor fire's track already on the floor (seen through a window from outside) was reported by every
    search at its first look, hot or cold: the central unit took those reports for sightings (which room
    sees the fire, a doubted fire found again). A search whose camera never sees it hot reports none."""
    agent, ual, be = ugv_inside
    o = Object(id=11, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_INDOOR, status=C.STATUS_ACTIVE, num_updates=5)
    o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = 17.7, 8.5, 1.0
    be.subs['/estimated_objects'](ObjectList(objects=[o]))
    be.handlers['thermal_detection/fire_detected'] = lambda r: CheckFireResponse(fire_detected=False)
    s, outcome = search(be)
    assert outcome == 'succeeded', s.result.message
    assert list(s.result.fire_ids) == [] and 'no indoor fire found' in s.result.message, s.result.message
