"""search_indoor with ~indoor_search explore, against a fake UAL, a ray-cast laser and a thermal camera that
sees a fire in straight sight ahead: the UGV, given only its door, finds a fire two doorways away in a floor
plan it was not told of, without driving near a wall; in plan mode the same search does not find it. The
UGV starts just inside its door (a search given again): the door's passage is test_passage's."""
import math

import pytest
from mbzirc_comm_objs.msg import Object, ObjectList, SearchIndoorGoal
from mbzirc_comm_objs.srv import CheckFireResponse

from fake_backend import FakeBackend
from fake_ual import start_ugv, stop_agent
from laser_world import LaserScene, wall_boxes
from mbzirc_agents import constants as C

# another floor plan than the default world's: a wall across y = 11.0..11.2 (doorway x 13-15) and a wall
# x = 18.0..18.2 north of it (doorway y 16-18); the fire on the east face of the latter
INNER = [(11.6, 11.0, 13.0, 11.2), (15.0, 11.0, 24.0, 11.2), (18.0, 11.2, 18.2, 16.0), (18.0, 18.0, 18.2, 19.3)]
FIRE = (18.25, 13.0, 1.5)
SEE = 5.0                      # m the fake camera sees a fire at (the detector's hot-frame laser gate)
HALF_FOV = math.radians(30)


def blocked(p, q, boxes, half=0.0, n=80):
    for k in range(n + 1):
        x, y = p[0] + (q[0] - p[0]) * k / n, p[1] + (q[1] - p[1]) * k / n
        if any(x0 - half < x < x1 + half and y0 - half < y < y1 + half for x0, y0, x1, y1 in boxes):
            return True
    return False


@pytest.fixture
def scene(request):
    mode = request.param
    be = FakeBackend()
    agent, ual = start_ugv(be, (14.25, 8.0, 0.0), {'check_fire_time': 1.0, 'indoor_search': mode,
                                                   'explore_budget': 600.0})
    ual.yaw = math.pi / 2
    ual.follow_velocity = True
    boxes = wall_boxes(0.9) + INNER
    laser = LaserScene(be, ual, laser_z=0.9, noisy=False)
    laser.boxes = boxes
    state = {'nearest': 9.9, 'stop': False, 'trace': []}

    def sees():
        p, yaw = ual.pos[:2], ual.yaw
        d = math.dist(p, FIRE[:2])
        off = math.atan2(FIRE[1] - p[1], FIRE[0] - p[0]) - yaw
        off = math.atan2(math.sin(off), math.cos(off))
        return d < SEE and abs(off) < HALF_FOV and not blocked(p, FIRE[:2], INNER)

    def camera(_req):
        hot = sees()
        if hot:                                  # the estimator's track of what the detector saw
            o = Object(id=7, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_INDOOR, status=C.STATUS_ACTIVE, num_updates=5)
            o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = FIRE
            be.subs['/estimated_objects'](ObjectList(objects=[o]))
        return CheckFireResponse(fire_detected=hot)

    be.handlers['thermal_detection/fire_detected'] = camera

    def watch():                                 # the UGV's true clearance from every wall, all along
        while not state['stop']:
            p = ual.pos[:2]
            if not state['trace'] or math.dist(state['trace'][-1], p) > 0.3:
                state['trace'].append((round(float(p[0]), 2), round(float(p[1]), 2)))
            for x0, y0, x1, y1 in boxes:
                dx, dy = max(x0 - p[0], 0, p[0] - x1), max(y0 - p[1], 0, p[1] - y1)
                state['nearest'] = min(state['nearest'], math.hypot(dx, dy))
            be.clock.sleep(0.05)

    be.clock.start_thread(watch, name='clearance watch')
    yield agent, ual, be, state
    state['stop'] = True
    stop_agent(agent, ual, be, laser)


def search(be):
    s = be.servers['search_indoor_action']
    s.send(SearchIndoorGoal(floor=0))
    return s, s.wait(900)


@pytest.mark.parametrize('scene', ['explore'], indirect=True)
def test_the_ugv_explores_through_two_doorways_to_the_fire(scene):
    agent, ual, be, state = scene
    s, outcome = search(be)
    assert outcome == 'succeeded', (s.result.message, state['trace'])
    assert list(s.result.fire_ids) == [7], s.result.message
    assert ual.pos[0] > 18.2 and ual.pos[1] > 11.2                 # in the north-east room
    assert state['nearest'] > 0.6, state['nearest']                 # UGV radius 0.6: it never touched a wall


@pytest.mark.parametrize('scene', ['plan'], indirect=True)
def test_the_planned_path_of_the_default_floor_plan_does_not_find_it(scene):
    agent, ual, be, state = scene
    s, outcome = search(be)
    assert not (outcome == 'succeeded' and list(s.result.fire_ids) == [7]), s.result.message
