"""extinguish_indoor_fire against a fake UAL and a scripted thermal camera: when water flows, when it
stops, and the top-up of a confirmed fire that reads cold."""
import pytest
from mbzirc_comm_objs.msg import ExtinguishIndoorFireGoal, Object, ObjectList, TakeOffGoal
from mbzirc_comm_objs.srv import CheckFireResponse

from fake_backend import FakeBackend
from fake_ual import start_uav, stop_agent
from mbzirc_agents import constants as C


class Scene:
    """A UAV in the air, one indoor fire track, a thermal camera answering from a script."""

    def __init__(self, hot_until=0.0, num_updates=50, std=0.2):
        self.be = FakeBackend()
        self.statuses = []
        self.hot_until = hot_until
        self.pumping_since = None
        self.be.handlers['thermal_detection/fire_detected'] = lambda r: CheckFireResponse(fire_detected=self.hot())
        self.be.handlers['/set_object_status'] = lambda r: self.statuses.append(r.object_status) or type('R', (), {})()
        self.agent, self.ual = start_uav(self.be, {'check_fire_time': 1.0, 'top_up_time': 1.0}, speedup=2.0)
        s = self.be.servers['take_off_action']
        s.send(TakeOffGoal(height=6.5))
        assert s.wait(10) == 'succeeded'
        o = Object(id=7, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_INDOOR, status=C.STATUS_LOST, num_updates=num_updates)
        o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = 4.0, 0.0, 6.5
        o.pose.covariance = [0.0] * 36
        o.pose.covariance[0] = o.pose.covariance[7] = o.pose.covariance[14] = std ** 2
        self.be.subs['/estimated_objects'](ObjectList(objects=[o]))

    def hot(self):
        """Hot until `hot_until` s of pumping (never seen hot when 0)."""
        if self.ual.pump and self.pumping_since is None:
            self.pumping_since = self.be.clock.now()
        if self.hot_until <= 0:
            return False
        return self.pumping_since is None or self.be.clock.now() - self.pumping_since < self.hot_until

    def extinguish(self):
        s = self.be.servers['extinguish_indoor_fire_action']
        s.send(ExtinguishIndoorFireGoal(fire_id=7))
        assert s.wait(30) in ('succeeded', 'aborted')
        return s

    def close(self):
        stop_agent(self.agent, self.ual, self.be)


@pytest.fixture
def scenes():
    made = []
    yield lambda **kw: made.append(Scene(**kw)) or made[-1]
    for s in made:
        s.close()


def test_water_flows_until_the_fire_reads_cold_several_times(scenes):
    sc = scenes(hot_until=1.0)
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]
    # hot 1 s of pumping, then C.COLD_CHECKS cold answers 0.5 s apart, water flowing
    used = 2.0 - sc.ual.water
    assert used >= 0.4 * (1.0 + 0.5 * (C.COLD_CHECKS - 1)) * 0.8, f'only {used:.2f} L pumped'


@pytest.mark.parametrize('std', [0.2, 0.75])
def test_a_confirmed_fire_that_reads_cold_is_topped_up(scenes, std):
    """std 0.75: a track at the estimator's GNSS floor (~pose_std 0.7 m) still counts as well localised
    (with a fixed 0.4 m bound no fire a dry tank left was ever topped up: one stayed at 85 %)."""
    sc = scenes(hot_until=0.0, std=std)
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished and 'topped up' in s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]
    assert 0.2 < 2.0 - sc.ual.water < 1.0          # ~1 s at 0.4 L/s (fake UAL at twice real time)


@pytest.mark.parametrize('updates,std', [(5, 0.2), (50, 1.5)])
def test_a_doubtful_track_that_reads_cold_gets_no_water(scenes, updates, std):
    sc = scenes(hot_until=0.0, num_updates=updates, std=std)
    s = sc.extinguish()
    assert s.status == 'aborted' and 'not in sight' in s.result.message
    assert sc.statuses == [] and sc.ual.water == 2.0


@pytest.mark.parametrize('water,out', [(0.6, False), (1.2, False), (2.0, False)])
def test_cold_only_after_the_tank_ran_dry(scenes, water, out):
    """Hot until the last drop, cold after it: a fire being filled cools in the thermal image, so it may be
    just short of full (seen: 1.2 L left a fire at 92 %) and stays active for a top-up, however much water
    was pumped (how much a fire needs is unknown: 0.8-1.3x nominal in the real arena)."""
    sc = scenes(hot_until=0.0)
    sc.ual.water = water
    sc.hot = lambda: sc.ual.water > 0.1
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished is out, s.result.message
    assert sc.statuses == ([C.STATUS_EXTINGUISHED] if out else [])
    assert sc.ual.water <= 0.1
    if not out:
        assert 'top-up' in s.result.message


def test_the_robot_turns_to_the_hot_spot_before_pumping(scenes):
    """The thermal camera sees the fire 0.3 rad to the left of the heading (the estimate was faced from a
    pose off by its GNSS error): the robot turns by that much before the water flows."""
    import math
    from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
    sc = scenes(hot_until=1.0)
    yaw0 = []

    def answer(_req):
        yaw0.append(sc.ual.yaw)
        det = ObjectDetection(type=C.TYPE_FIRE)       # where the camera sees it, from the current heading
        det.relative_position.x = 1.5
        det.relative_position.y = 1.5 * math.tan(0.3 - (sc.ual.yaw - yaw0[0]))
        sc.be.subs['sensed_objects'](ObjectDetectionList(objects=[det]))
        return CheckFireResponse(fire_detected=sc.hot())
    sc.be.handlers['thermal_detection/fire_detected'] = answer
    s = sc.extinguish()
    assert s.status == 'succeeded', s.result.message
    assert sc.ual.yaw == pytest.approx(yaw0[0] + 0.3, abs=0.05)
