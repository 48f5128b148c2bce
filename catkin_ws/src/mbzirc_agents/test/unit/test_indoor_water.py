"""extinguish_indoor_fire against a fake UAL and a scripted thermal camera: when water flows, when it
stops, when a fire is judged out (seen hot from the watering pose, watered, then cold: tasks/cold_check.py)
and the top-up of a confirmed fire that reads cold (water, never a verdict of "out")."""
import math

import numpy as np
import pytest
from mbzirc_comm_objs.msg import ExtinguishIndoorFireGoal, Object, ObjectList, TakeOffGoal
from mbzirc_comm_objs.srv import CheckFireResponse

import fake_thermal
from fake_backend import FakeBackend
from fake_ual import start_ugv, start_uav, stop_agent
from mbzirc_agents import constants as C


FIRE = (4.0, 0.0, 6.5)      # the fire (track and truth); the UAV waters it from 1.5 m, at (2.5, 0, 6.5) facing +x
FOCAL = 16.0 / math.tan(math.radians(33.0) / 2.0)   # px: the 32 px wide, 33 deg thermal camera


def frame_at(contrast, bearing, rise_angle, rng):
    """A raw frame (fake_thermal.fire_frame) with the fire's centre `bearing` rad left of the optical axis and
    `rise_angle` rad above it: what the camera shows of a fire its detection puts there."""
    return fake_thermal.fire_frame(contrast, rng=rng, centre=(15.5 - FOCAL * math.tan(rise_angle),
                                                              15.5 - FOCAL * math.tan(bearing)))


class Scene:
    """A UAV in the air, one indoor fire track, a thermal camera answering from a script."""

    def __init__(self, hot_until=0.0, num_updates=50, std=0.2, params=None):
        self.be = FakeBackend()
        self.statuses = []
        self.hot_until = hot_until
        self.pumping_since = None
        self.threads = ()            # the scene's own threads (objects with a `stop` flag), stopped with it
        self.be.handlers['thermal_detection/fire_detected'] = lambda r: CheckFireResponse(fire_detected=self.hot())
        self.be.handlers['/set_object_status'] = lambda r: self.statuses.append(r.object_status) or type('R', (), {})()
        self.agent, self.ual = start_uav(self.be, {'check_fire_time': 1.0, 'top_up_time': 1.0, **(params or {})},
                                          speedup=2.0)
        # the raw thermal image follows the script: the fire far over its wall while hot, at the wall's level
        # (out) when cold; tests of a fire that fades out of the detector's sight set their own
        rng = np.random.default_rng(1)
        self.ual.thermal = lambda: fake_thermal.fire_frame(60.0 if self.hot() else 0.0, rng=rng)
        s = self.be.servers['take_off_action']
        s.send(TakeOffGoal(height=6.5))
        assert s.wait(10) == 'succeeded'
        o = Object(id=7, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_INDOOR, status=C.STATUS_LOST, num_updates=num_updates)
        o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = FIRE
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

    def extinguish(self, timeout=30):
        s = self.be.servers['extinguish_indoor_fire_action']
        s.send(ExtinguishIndoorFireGoal(fire_id=7))
        assert s.wait(timeout) in ('succeeded', 'aborted')
        return s

    def close(self):
        stop_agent(self.agent, self.ual, self.be, *self.threads)


@pytest.fixture
def scenes():
    made = []
    yield lambda **kw: made.append(Scene(**kw)) or made[-1]
    for s in made:
        s.close()


def test_water_flows_until_the_fire_is_soaked_then_it_is_confirmed_cold_with_the_pump_off(scenes):
    sc = scenes(hot_until=1.0)
    stops = []
    stop = sc.be.handlers['actuators_system/stop_pump']
    sc.be.handlers['actuators_system/stop_pump'] = lambda r: stops.append(sc.be.clock.now()) or stop(r)
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]
    # hot 1 s of pumping, then a soak of at least ~soak_min_time (1 s) with water flowing
    used = 2.0 - sc.ual.water
    assert used >= 0.4 * 2.0 * 0.8, f'only {used:.2f} L pumped'
    # then C.COLD_CHECKS cold answers (0.5 s apart) with the pump off: no water for them
    assert len(stops) >= 2, 'the pump was not stopped before the cold answers'
    assert stops[-1] - stops[0] >= 0.5 * (C.COLD_CHECKS - 1), f'confirmed in {stops[-1] - stops[0]:.1f} s'
    assert used <= 0.4 * 3.5, f'{used:.2f} L pumped: water flowed while the cold answers were counted'


def test_the_raw_thermal_image_is_subscribed_only_while_the_task_runs(scenes):
    """Each raw frame a subscriber gets is deserialised (14 a sim-second per robot): the task that reads them
    subscribes when it starts and unregisters when it ends, so an agent pays for them only then."""
    sc = scenes(hot_until=1.0)
    assert fake_thermal.TOPIC not in sc.be.subs, 'subscribed before the task runs'
    seen = []
    sc.ual.thermal = (lambda f=sc.ual.thermal: seen.append(fake_thermal.TOPIC in sc.be.subs) or f())
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    sc.be.clock.sleep(0.5)                 # the subscription is closed in a thread of its own
    assert fake_thermal.TOPIC not in sc.be.subs, 'still subscribed after the task ended'
    assert any(seen)


@pytest.mark.parametrize('std', [0.2, 0.75])
def test_a_fire_never_seen_hot_from_the_watering_pose_is_not_judged_out(scenes, std):
    """A confirmed, well-localised track that reads cold gets ~top_up_time of water (a fire being filled reads
    cold for its last part), but is not marked out: cold there may mean "not looking at it" (mission seed 3:
    a fire at 63 % was reported out by a top-up that never saw it). The goal fails, so that the central unit
    tries again or gives the fire to another robot. std 0.75: a track at the estimator's GNSS floor
    (~pose_std 0.7 m) still counts as well localised for the water."""
    sc = scenes(hot_until=0.0, std=std)
    s = sc.extinguish()
    assert s.status == 'aborted' and 'not seen hot from the watering pose' in s.result.message, s.result.message
    assert 'not judged out' in s.result.message
    assert sc.statuses == []
    assert 0.2 < 2.0 - sc.ual.water < 1.0          # ~1 s at 0.4 L/s (fake UAL at twice real time)


def test_a_fire_that_shows_hot_during_the_top_up_is_watered_until_cold(scenes):
    """Cold at the check, hot once water flows at it from the watering pose, cold after more water: seen,
    watered, cold: out (3 L: 1 L to cold, a soak of a quarter of it, then the cold check's 6 answers)."""
    sc = scenes(hot_until=0.0)
    sc.ual.water = 3.0
    sc.hot = lambda: sc.ual.pump and sc.ual.water > 2.0
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert 'topped up' not in s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]


class FireModel:
    """The scene's referee: the fire gets water only while the pump runs with the UAV facing it (within
    0.1 rad), and its thermal camera reads it hot only while it faces it and the fire has had less than `need`
    s of water."""

    def __init__(self, sc, need):
        self.sc, self.need, self.received, self.stop = sc, need, 0.0, False
        sc.hot = self.hot
        sc.be.clock.start_thread(self._loop, name='fire model')

    def facing(self):
        u = self.sc.ual
        bearing = math.atan2(FIRE[1] - u.pos[1], FIRE[0] - u.pos[0])
        return abs(math.remainder(u.yaw - bearing, 2 * math.pi)) < 0.1

    def hot(self):
        return self.facing() and self.received < self.need

    def _loop(self):
        dt = 0.02
        while not self.stop:
            if self.sc.ual.pump and self.sc.ual.water > 0 and self.facing():
                self.received += dt
            self.sc.be.clock.sleep(dt)


class Gust:
    """Turns the UAV away from the fire (the yaw of its UAL set-point) for `seconds`, once the fire had
    `after` s of water: its thermal camera reads cold because it looks at the wall."""

    def __init__(self, sc, fire, after, seconds, yaw=1.0):
        self.sc, self.fire, self.after, self.seconds, self.yaw, self.stop = sc, fire, after, seconds, yaw, False
        sc.be.clock.start_thread(self._loop, name='gust')

    def _loop(self):
        clock, ual = self.sc.be.clock, self.sc.ual
        while not self.stop and self.fire.received < self.after:
            clock.sleep(0.02)
        end = clock.now() + self.seconds
        while not self.stop and clock.now() < end:
            with ual.lock:
                if ual.goal is not None:
                    ual.goal = (ual.goal[0], self.yaw)
            clock.sleep(0.02)


def test_seen_hot_watered_then_cold_is_out(scenes):
    sc = scenes()
    fire = FireModel(sc, need=1.0)
    sc.threads = (fire,)
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]
    assert fire.received >= fire.need


def test_cold_while_the_robot_looks_away_is_not_out(scenes):
    """Seen hot and watered, then turned away for 4 s (6 cold answers would fit in 3): those answers say
    nothing; back at the watering pose it waters on until the fire reads cold there."""
    sc = scenes()
    sc.ual.water = 6.0
    fire = FireModel(sc, need=1.0)
    gust = Gust(sc, fire, after=0.2, seconds=4.0)
    sc.threads = (fire, gust)
    s = sc.extinguish()
    assert fire.received >= fire.need or not s.result.extinguished, \
        f'reported out after {fire.received:.2f} s of water of {fire.need:.2f}: {s.result.message}'
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]


def test_cold_without_water_flowing_is_not_out(scenes):
    """Seen hot, the pump says it started but the tank level never drops (no water at the fire), then the
    fire reads cold: not out, the goal fails with the reason."""
    from std_srvs.srv import TriggerResponse
    sc = scenes()
    started = []
    sc.be.handlers['actuators_system/start_pump'] = lambda r: started.append(sc.be.clock.now()) or \
        TriggerResponse(success=True, message='')
    sc.hot = lambda: not started or sc.be.clock.now() - started[0] < 1.0
    s = sc.extinguish()
    assert s.status == 'aborted' and 'water' in s.result.message, s.result.message
    assert not s.result.extinguished
    assert sc.statuses == [] and sc.ual.water == 2.0


def test_hot_before_turning_to_the_hot_spot_but_not_after_is_not_out(scenes):
    """The check saw the fire hot, the camera's detection was 0.3 rad aside, the robot turned there and then
    reads cold, detector and raw image (seed 109's rule: a raw image showing it hot there would do): it never
    saw the fire hot from the pose it waters from."""
    from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
    sc = scenes(hot_until=10.0)
    yaw0 = []

    def answer(_req):
        yaw0.append(sc.ual.yaw)
        det = ObjectDetection(type=C.TYPE_FIRE)
        det.relative_position.x = 1.5
        det.relative_position.y = 1.5 * math.tan(0.3 - (sc.ual.yaw - yaw0[0]))
        sc.be.subs['sensed_objects'](ObjectDetectionList(objects=[det]))
        return CheckFireResponse(fire_detected=abs(sc.ual.yaw - yaw0[0]) < 0.05)
    sc.be.handlers['thermal_detection/fire_detected'] = answer
    rng = np.random.default_rng(2)           # the raw image: the fire where the detection says, until the turn
    turned = lambda: bool(yaw0) and abs(sc.ual.yaw - yaw0[0]) >= 0.05
    sc.ual.thermal = lambda: frame_at(0.0 if turned() else 60.0, 0.3 - (sc.ual.yaw - yaw0[0] if yaw0 else 0.0),
                                      0.0, rng)
    s = sc.extinguish()
    assert s.status == 'aborted' and 'not seen hot from the watering pose' in s.result.message, s.result.message
    assert sc.statuses == []


@pytest.mark.parametrize('updates,std', [(5, 0.2), (50, 1.5)])
def test_a_doubtful_track_that_reads_cold_gets_no_water(scenes, updates, std):
    sc = scenes(hot_until=0.0, num_updates=updates, std=std)
    s = sc.extinguish()
    assert s.status == 'aborted' and 'not in sight' in s.result.message
    assert sc.statuses == [] and sc.ual.water == 2.0


@pytest.mark.parametrize('water', [0.6, 1.2, 2.0])
def test_a_fire_hot_while_any_water_flowed_is_left_for_a_top_up_when_the_tank_runs_dry(scenes, water):
    """Hot while water flows, whatever the tank held, cold once the pump stopped on the dry tank: it never read
    cold while water flowed at it, so no soak began, and how much water a fire needs is unknown (0.8-1.3x
    nominal in the real arena): it stays active for a top-up, with no verdict from the litres pumped."""
    sc = scenes(hot_until=0.0)
    sc.ual.water = water
    sc.hot = lambda: sc.ual.pump
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished is False, s.result.message
    assert sc.statuses == [] and sc.ual.water <= 0.1
    assert 'top-up' in s.result.message


def test_a_fire_that_read_cold_with_water_flowing_and_whose_tank_ran_dry_while_soaking_is_confirmed_without_water(
        scenes):
    """Cold with water flowing 1.5 L before the tank ran dry (of 10 L): the soak (a quarter of the ~8.3 L that
    made it read cold) began and the tank ran dry in it, past ~dry_soak_min_share of it. The robot confirms with the pump off, as
    after a whole soak: 6 cold answers in a row in the raw thermal image (at its wall's level) and it is out;
    no top-up trip for a fire already put out. (Before: 'the tank ran dry before 6 cold answers (0 so far)' on
    fires put out by their first tank, ual_sim's realistic profile: 35 of 72 closed-loop pours,
    test_indoor_closed_loop.py.)"""
    sc = scenes(hot_until=0.0)
    sc.ual.water = 10.0                  # cold with 1.5 L left: a soak of ~2.1 L cut at ~70 % (margins for timing)
    sc.hot = lambda: sc.ual.water > 1.5
    s = sc.extinguish(timeout=90)
    assert s.status == 'succeeded' and s.result.extinguished is True, s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED] and sc.ual.water <= 0.1
    assert any('ran dry while soaking' in m for m in sc.be.infos), sc.be.infos


def test_a_soak_the_tank_cut_short_at_its_start_leaves_the_fire_for_a_top_up(scenes):
    """Cold with water flowing only as the last 0.4 L left the tank: the soak, the margin past the point where
    a fire stops showing, had under ~dry_soak_min_share of its litres. Not confirmed out, left for a top-up
    (closed loop, ual_sim's realistic profile: tanks dry 0-22 % into the soak left fires at 99.5-99.99 %
    confirmed out; bench_indoor_pour.py)."""
    sc = scenes(hot_until=0.0)
    sc.ual.water = 10.0                  # cold with 0.4 L left: a soak of ~2.3 L (a quarter of ~9.4 L) cut at ~17 %
    sc.hot = lambda: sc.ual.water > 0.4
    s = sc.extinguish(timeout=90)
    assert s.status == 'succeeded' and s.result.extinguished is False, s.result.message
    assert sc.statuses == [] and 'into the soak' in s.result.message and 'top-up' in s.result.message


def test_a_fire_that_shows_hot_again_after_a_soak_cut_short_by_a_dry_tank_is_left_for_a_top_up(scenes):
    """Cold with water flowing, the tank dry in the soak, then hot again with the pump off: it still burns,
    and there is no water to give it: not out, left for a top-up."""
    sc = scenes(hot_until=0.0)
    sc.ual.water = 10.0
    cold_from = []

    def hot():
        if sc.ual.water > 1.5:
            return True
        cold_from.append(sc.be.clock.now())
        return sc.be.clock.now() - cold_from[0] > 5.0        # cold for 5 s (the tank dry by then), then hot
    sc.hot = hot
    s = sc.extinguish(timeout=90)
    assert s.status == 'succeeded' and s.result.extinguished is False, s.result.message
    assert sc.statuses == [] and 'top-up' in s.result.message


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
    rng = np.random.default_rng(2)           # the raw image shows the fire where the detection says
    sc.ual.thermal = lambda: frame_at(60.0 if sc.hot() else 0.0, 0.3 - (sc.ual.yaw - yaw0[0] if yaw0 else 0.0),
                                      0.0, rng)
    s = sc.extinguish()
    assert s.status == 'succeeded', s.result.message
    assert sc.ual.yaw == pytest.approx(yaw0[0] + 0.3, abs=0.05)


class ForwardCamera:
    """Thermal detections of the fire at FIRE (~10 Hz) from the UAV's true pose and heading, the bearing
    under-read by a third (a 32-pixel image: the centroid of a flame ring partly out of view is pulled to
    the image centre), so that one turn by the bearing read falls short of the hot spot."""

    def __init__(self, sc, scale=0.7):
        self.sc, self.scale, self.stop = sc, scale, False
        rng = np.random.default_rng(2)      # the raw image: the fire where it is (its centre, the hole)
        sc.ual.thermal = lambda: frame_at(60.0 if sc.hot() else 0.0, self.true_bearing()[0], 0.0, rng)
        sc.be.clock.start_thread(self._loop, name='forward camera')

    def true_bearing(self):
        u = self.sc.ual
        with u.lock:
            pos, yaw = u.pos.copy(), u.yaw
        return math.remainder(math.atan2(FIRE[1] - pos[1], FIRE[0] - pos[0]) - yaw, 2 * math.pi), pos

    def _loop(self):
        from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
        be = self.sc.be
        while not self.stop:
            bearing, pos = self.true_bearing()
            d = math.hypot(FIRE[0] - pos[0], FIRE[1] - pos[1])
            if abs(bearing) < 0.3 and 'sensed_objects' in be.subs:
                det = ObjectDetection(type=C.TYPE_FIRE)
                det.header.stamp.secs, det.header.stamp.nsecs = divmod(int(be.clock.now() * 1e9), 10 ** 9)
                det.relative_position.x = d * math.cos(self.scale * bearing)
                det.relative_position.y = d * math.sin(self.scale * bearing)
                det.image_detection.camera_direction = C.CAMERA_FORWARD
                be.subs['sensed_objects'](ObjectDetectionList(objects=[det]))
            be.clock.sleep(0.1)


def test_the_robot_turns_until_the_hot_spot_is_straight_ahead(scenes):
    """A GNSS error of 0.45 m sideways puts the watering pose beside the fire (0.29 rad off the heading);
    the camera under-reads the bearing: turns, each measured again on a new image, until the fire is ahead
    (one turn by the first bearing read left the jet 0.09 rad, 0.13 m, beside it)."""
    sc = scenes(hot_until=1.0)
    sc.ual.gnss_bias = np.array([0.0, 0.45, 0.0])
    cam = ForwardCamera(sc)
    sc.threads = (cam,)
    aims = []
    start_pump = sc.be.handlers['actuators_system/start_pump']
    sc.be.handlers['actuators_system/start_pump'] = lambda r: aims.append(cam.true_bearing()[0]) or start_pump(r)
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert aims and abs(aims[0]) <= 0.05, f'the jet left {aims[0]:.3f} rad off the fire'


class GnssDrift:
    """Once the pump runs: nothing holds the robot's set-point any more (a UGV parked, as ual_sim's) and its
    GNSS error drifts 0.7 m sideways over 3 s; the robot's true position never changes by itself."""

    def __init__(self, sc):
        self.sc, self.stop, self.start_pos = sc, False, None
        sc.be.clock.start_thread(self._loop, name='gnss drift')

    def _loop(self):
        ual, clock = self.sc.ual, self.sc.be.clock
        while not self.stop and not ual.pump:
            clock.sleep(0.02)
        with ual.lock:
            ual.goal = None
            self.start_pos = ual.pos.copy()
        t0 = clock.now()
        while not self.stop and clock.now() - t0 < 3.0:
            with ual.lock:
                ual.gnss_bias = np.array([0.0, 0.7 * (clock.now() - t0) / 3.0, 0.0])
            clock.sleep(0.02)


def test_the_gnss_error_drifting_does_not_drive_the_robot_off_where_it_waters_from(scenes):
    """Seen hot, pumping; the reported position drifts 0.7 m away: the robot stays where it stands and
    waters on (a drive back to the pose's GNSS position moved seed 103's UGV 0.37 m, its jet 0.5 m beside
    the hole). Cold answers beyond the watering pose's tolerance still say nothing."""
    sc = scenes(hot_until=10.0)
    drift = GnssDrift(sc)
    sc.threads = (drift,)
    s = sc.extinguish()
    assert drift.start_pos is not None
    moved = float(np.linalg.norm(sc.ual.pos[:2] - drift.start_pos[:2]))
    assert moved < 0.1, f'driven {moved:.2f} m by the GNSS drift'
    assert sc.statuses == []


class LevelCamera:
    """Thermal detections (~10 Hz) of the fire at FIRE from the UAV's true pose: bearing and the hot spot's
    height above the camera axis (the camera and the nozzle level on the body axis), seen only within the
    image (+-0.28 rad either way). The referee: water enters the fire only while the pump runs with the
    jet's true spot within `hit` m of the hole's centre (a 0.15 m hole, a spot of ~0.1 m), and the camera reads
    the fire hot while it is in the image and has had less than `need` s of water."""

    scale = 1.0         # the detector's reading of the fire's offset from the image centre, x the true one

    def __init__(self, sc, need=1.0, hit=0.08):
        self.sc, self.need, self.hit, self.received, self.stop = sc, need, hit, 0.0, False
        sc.hot = self.hot
        rng = np.random.default_rng(2)      # the raw image: the fire where the detections put it

        sc.ual.thermal = lambda: self.frame(rng)
        sc.be.clock.start_thread(self._loop, name='level camera')

    def view(self):
        u = self.sc.ual
        with u.lock:
            pos, yaw = u.pos.copy(), u.yaw
        d = math.hypot(FIRE[0] - pos[0], FIRE[1] - pos[1])
        bearing = math.remainder(math.atan2(FIRE[1] - pos[1], FIRE[0] - pos[0]) - yaw, 2 * math.pi)
        return d, bearing, FIRE[2] - pos[2]

    def in_image(self):
        d, bearing, rise = self.view()
        return abs(bearing) < 0.28 and abs(math.atan2(rise, d)) < 0.28

    def jet_miss(self):
        d, bearing, rise = self.view()
        return math.hypot(d * math.tan(bearing), rise)

    def hot(self):
        return self.in_image() and self.received < self.need

    def frame(self, rng):
        d, bearing, rise = self.view()
        return frame_at(60.0 if self.hot() else 0.0, bearing, math.atan2(rise, d), rng)

    def _loop(self):
        from mbzirc_comm_objs.msg import ObjectDetection, ObjectDetectionList
        be, dt, tick = self.sc.be, 0.02, 0
        while not self.stop:
            if self.sc.ual.pump and self.sc.ual.water > 0 and self.jet_miss() <= self.hit:
                self.received += dt
            tick += 1
            if tick % 5 == 0 and self.hot() and 'sensed_objects' in be.subs:
                d, bearing, rise = self.view()
                det = ObjectDetection(type=C.TYPE_FIRE)
                det.header.stamp.secs, det.header.stamp.nsecs = divmod(int(be.clock.now() * 1e9), 10 ** 9)
                det.relative_position.x = d * math.cos(self.scale * bearing)
                det.relative_position.y = d * math.sin(self.scale * bearing)
                det.relative_position.z = self.scale * rise
                det.image_detection.camera_direction = C.CAMERA_FORWARD
                be.subs['sensed_objects'](ObjectDetectionList(objects=[det]))
            be.clock.sleep(dt)


@pytest.mark.parametrize('bias_z', [0.4, -0.35])
def test_the_uav_steers_its_height_onto_the_hot_spot(scenes, bias_z):
    """The GNSS height reads bias_z m off the truth (realistic: 0.3-0.5 m): the watering pose's height (the
    fire estimate's) puts the jet that far above or below the 0.15 m hole, and 2 L went beside it (realistic
    seed 108: floor-1/2 fires left at 13-91 %). Steered on the thermal image, the jet reaches the hole: the
    fire gets its water and is put out with the tank's 2 L."""
    sc = scenes()
    sc.ual.gnss_bias = np.array([0.0, 0.0, bias_z])
    cam = LevelCamera(sc)
    sc.threads = (cam,)
    s = sc.extinguish()
    assert cam.received >= cam.need, f'{cam.received:.2f} s of water in of {cam.need:.2f}: {s.result.message}'
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]
    assert abs(cam.view()[2]) <= 0.1


def test_a_fire_beyond_the_height_the_uav_may_steer_to_is_not_judged_out_from_there(scenes):
    """The hot spot 0.4 m above the jet, the UAV allowed to climb only 0.15 m (~aim_height_range): the jet
    stays below the hole, the fire never gets its water; when it then reads cold (out of the image: the GNSS
    height error grows), that cold says nothing and the fire is not reported out."""
    sc = scenes()
    sc.agent.p.aim_height_range = 0.15
    sc.ual.gnss_bias = np.array([0.0, 0.0, 0.4])
    sc.ual.water = 3.0
    cam = LevelCamera(sc)

    class Sinking:                           # once the pump runs, the GNSS height error grows by 0.5 m
        stop, done = False, False

        def __init__(self):
            sc.be.clock.start_thread(self.loop, name='sinking')

        def loop(self):
            while not self.stop and not sc.ual.pump:
                sc.be.clock.sleep(0.02)
            sc.be.clock.sleep(1.0)
            with sc.ual.lock:
                sc.ual.gnss_bias = np.array([0.0, 0.0, 1.0])
            self.done = True
    sinking = Sinking()
    sc.threads = (cam, sinking)
    s = sc.extinguish()
    assert cam.received < cam.need and sinking.done
    assert not s.result.extinguished, s.result.message
    assert sc.statuses == []


class RingCamera(LevelCamera):
    """LevelCamera of a holder seen from its watering distance: a ring of flames wider than the view around
    the hole (fake_thermal.ring_frame), and a detector whose centroid of the ring's part in the frame reads a
    fifth of the hole's true offset from the image centre (ual_sim's realistic world, a UAV 1.2 m from the
    wall: 1.4 of 6 deg)."""
    scale = 0.2

    def frame(self, rng):
        d, bearing, rise = self.view()
        centre = (15.5 - FOCAL * rise / d, 15.5 - FOCAL * math.tan(bearing))
        return fake_thermal.ring_frame(200.0 if self.hot() else 0.0, centre, outer=24.0, rng=rng)


class SideDrift:
    """Once the pump runs: the GNSS error wanders sideways at `rate` m/s up to `limit` m (ual_sim's realistic
    bias: ~0.18 m in 2 s); the UAL holds its set-point on the fix, so the UAV and its jet move the other way.
    axis 0: along x instead (towards the fire's wall at FIRE when rate < 0)."""

    def __init__(self, sc, rate=0.06, limit=0.3, axis=1):
        self.sc, self.rate, self.limit, self.stop, self.started = sc, rate, limit, False, False
        self.axis = axis
        sc.be.clock.start_thread(self._loop, name='side drift')

    def _loop(self):
        ual, clock = self.sc.ual, self.sc.be.clock
        while not self.stop and not ual.pump:
            clock.sleep(0.02)
        self.started, t0 = True, clock.now()
        while not self.stop:
            with ual.lock:
                bias = np.zeros(3)
                bias[self.axis] = math.copysign(min(self.limit, abs(self.rate) * (clock.now() - t0)), self.rate)
                ual.gnss_bias = bias
            clock.sleep(0.02)


def test_the_jet_follows_the_hole_a_ring_of_flames_filling_the_view_rings_while_the_uav_drifts_sideways(scenes):
    """Issue 17 (realistic seed 103: three full tanks left in1_e at 86 %): from the watering distance the ring
    of flames fills the thermal camera's view, the detector's centroid hardly moves as the UAV drifts sideways
    with its GNSS fix, and the aim stayed beside the 0.15 m hole. Aimed on the hole the raw image shows, the
    jet stays within 6 cm of its centre and the fire gets its water and is put out. Before: 1.0 s of water in of
    3.0 (the jet 0.15 rad off before a detection's bearing turned it), the tank ran dry with the fire burning."""
    sc = scenes()
    sc.ual.water = 3.0
    cam = RingCamera(sc, need=3.0, hit=0.06)
    drift = SideDrift(sc)
    sc.threads = (cam, drift)
    s = sc.extinguish()
    assert drift.started
    assert cam.received >= cam.need, f'{cam.received:.2f} s of water in of {cam.need:.2f}: {s.result.message}'
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message


class FadingCamera(LevelCamera):
    """LevelCamera whose fire stops showing (no detection, CheckFire cold) once it had `fade` of its need:
    its heat falls under the detector's contrast test while it still burns (realistic missions: at ~85 %)."""

    def __init__(self, sc, need, fade=0.85):
        self.fade = fade
        super().__init__(sc, need=need)

    def hot(self):
        return self.in_image() and self.received < self.fade * self.need


class HeightDrift:
    """Once the fire no longer shows: the GNSS height error wanders `rate` m/s up to `limit` m (the UAL holds
    its set-point on the GNSS height, so the true height, and the jet, move the other way)."""

    def __init__(self, sc, cam, rate=0.1, limit=0.4):
        self.sc, self.cam, self.rate, self.limit, self.stop, self.started = sc, cam, rate, limit, False, False
        sc.be.clock.start_thread(self._loop, name='height drift')

    def _loop(self):
        ual, clock = self.sc.ual, self.sc.be.clock
        while not self.stop and self.cam.received < self.cam.fade * self.cam.need:
            clock.sleep(0.02)
        self.started, t0 = True, clock.now()
        while not self.stop:
            with ual.lock:
                ual.gnss_bias = np.array([0.0, 0.0, min(self.limit, self.rate * (clock.now() - t0))])
            clock.sleep(0.02)


def test_a_fire_that_stops_showing_before_it_is_out_is_soaked_on_a_frozen_aim(scenes):
    """The fire stops showing at 85 % of its water and the GNSS height then drifts 0.1 m/s: the first cold
    answer starts a soak (a share of the water that made it read cold) on the aim that put water in, the
    height held by the altimeter; the fire gets its water and only then is reported out. Before: the cold
    check counted at once while the jet drifted off the hole, and the fire was reported out at ~90 %."""
    sc = scenes()
    sc.ual.water = 12.0
    cam = FadingCamera(sc, need=8.0)
    drift = HeightDrift(sc, cam)
    sc.threads = (cam, drift)
    s = sc.extinguish()
    assert drift.started
    assert cam.received >= cam.need or not s.result.extinguished, \
        f'reported out after {cam.received:.2f} s of water of {cam.need:.2f}: {s.result.message}'
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert sc.statuses == [C.STATUS_EXTINGUISHED]


class FadingFire:
    """The scene's fire as water puts it out: `need` L (all the water goes in), a raw contrast to its wall of
    `heat` deg C untouched that fades in proportion to the water still missing, on a wall at `wall` deg C (a
    sun-heated one with a `gradient` across the frame, the camera `offset` off, pixel `noise`), and a detector
    that reports it only while that contrast is over `seen_share` of its untouched heat (ideal missions: fires
    that fill the close view stopped being reported at 60-85 % watered)."""

    def __init__(self, sc, need, start_water, heat=60.0, seen_share=0.35, wall=31.0, gradient=0.0, offset=0.0,
                 noise=0.5, missing_at_least=0.0):
        self.sc, self.need, self.heat, self.seen_share = sc, need, heat, seen_share
        self.missing_at_least = missing_at_least     # share of the heat water never removes (a fire it misses)
        sc.ual.water = self.start_water = start_water
        rng = np.random.default_rng(3)
        sc.hot = lambda: self.contrast() > seen_share * heat
        sc.ual.thermal = lambda: fake_thermal.fire_frame(self.contrast(), wall=wall, gradient=gradient,
                                                         offset=offset, noise=noise, rng=rng)

    def progress(self):
        return min(1.0, (self.start_water - self.sc.ual.water) / self.need)

    def contrast(self):
        return self.heat * max(1.0 - self.progress(), self.missing_at_least)


def test_a_fire_fading_out_of_the_detectors_sight_is_watered_until_it_reads_at_its_walls_level(scenes):
    """Issue 17 (ideal missions: fires judged out at 85 % and 98.5 % watered): the detector stops reporting the
    fire at 55 % watered while it still stands 45 degC over its wall; before, its silence started the soak
    and the cold check, and the fire was reported out before it had its water (next test). Now cold is judged
    on the raw thermal image (the locked fire at ~out_contrast over its wall): out only once it had all its
    water."""
    sc = scenes(hot_until=1.0)
    fire = FadingFire(sc, need=10.0, start_water=14.0, heat=100.0, seen_share=0.45)
    s = sc.extinguish(timeout=60)
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert fire.progress() >= 1.0, f'judged out at {fire.progress():.3f} of its water'


@pytest.mark.parametrize('need, wall, gradient, offset, noise', [
    (0.8, 31.0, 0.0, 0.0, 0.5),
    (1.0, 45.0, 12.0, 3.0, 0.8),       # a sun-heated wall with a slope, the camera reading 3 degC high
    (1.3, 31.0, 0.0, -2.0, 1.0),
    (1.3, 55.0, 20.0, 0.0, 0.5)])
def test_a_full_tank_puts_out_a_fire_needing_up_to_1_3_nominal_and_confirms_it_without_running_dry(
        scenes, need, wall, gradient, offset, noise):
    """Water economy (a 2 L tank, a fire needing 0.8-1.3 L: the arena's spread around its 1 L nominal): soaked,
    then judged out on cold answers with the pump off, with water left. Before, the cold answers were counted
    with water flowing (6 answers: ~1.2 L at this fake pump's 0.4 L/s, ~1.6 L in missions): the tank ran dry
    on a fire already out ('the tank ran dry before 6 cold answers'), which stayed active for a top-up trip."""
    sc = scenes(hot_until=1.0)
    fire = FadingFire(sc, need=need, start_water=2.0, heat=50.0, wall=wall, gradient=gradient, offset=offset,
                      noise=noise)
    s = sc.extinguish(timeout=60)
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert fire.progress() >= 1.0, f'judged out at {fire.progress():.3f} of its water'
    assert sc.ual.water > 0.05, f'{sc.ual.water:.2f} L left: the tank ran dry on it'


def test_realistic_103_a_uav_beside_a_wall_backs_off_it_before_its_approach(scenes):
    """Realistic seed 103: two UAVs that a search left 0.3 m from a wall beside them (their GNSS fix 1.3 m off)
    hit it on the approach's first leg. Now the robot first backs off walls nearer than ~min_wall_clearance
    by its laser: along the approach it stays clear of the wall beside it. Before: the approach's leg started
    0.3 m from it (here the leg guard then held the leg, 'a laser return 0.00 m ahead': no water for the fire;
    in the mission the UAVs hit the wall)."""
    from laser_world import LaserScene
    sc = scenes(hot_until=2.0)
    laser = LaserScene(sc.be, sc.ual, noisy=False)
    laser.boxes = [(-5.0, 0.3, 10.0, 0.5), (4.05, -5.0, 4.25, 5.0)]     # a wall 0.3 m to the left, the fire's
    sc.threads = (laser,)
    sc.be.clock.sleep(0.5)                                               # its first scans
    track = []
    sc.be.clock.start_thread(lambda: [track.append(tuple(sc.ual.pos)) or sc.be.clock.sleep(0.05)
                                      for _ in range(600)], name='track')
    sc.extinguish(timeout=60)
    moved = [p for p in track if p[0] > 0.5]
    assert moved, 'the UAV never moved towards the fire'
    nearest = min(0.3 - p[1] for p in moved)
    assert nearest >= 0.7, f'{nearest:.2f} m from the wall beside it on the approach'


class UgvScene(Scene):
    """The UGV at its watering pose, 1.5 m from a ground-floor fire, facing it; the thermal camera scripted."""

    def __init__(self, hot_until=0.0, params=None):
        self.be = FakeBackend()
        self.statuses, self.hot_until, self.pumping_since, self.threads = [], hot_until, None, ()
        self.be.handlers['thermal_detection/fire_detected'] = lambda r: CheckFireResponse(fire_detected=self.hot())
        self.be.handlers['/set_object_status'] = lambda r: self.statuses.append(r.object_status) or type('R', (), {})()
        self.agent, self.ual = start_ugv(self.be, (2.5, 0.0, 0.0), {'check_fire_time': 1.0, 'top_up_time': 1.0,
                                                                     'wall_clearance': False, **(params or {})},
                                       speedup=2.0)
        o = Object(id=7, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_INDOOR, status=C.STATUS_LOST, num_updates=50)
        o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = 4.0, 0.0, 0.75
        o.pose.covariance = [0.0] * 36
        o.pose.covariance[0] = o.pose.covariance[7] = o.pose.covariance[14] = 0.2 ** 2
        self.be.subs['/estimated_objects'](ObjectList(objects=[o]))


class WanderingFix:
    """The GNSS fix of a robot standing still wanders (`rate` m/s on each axis, z too) once it pumps: a UGV at
    rest does not follow its fix (realistic profile: a 0.5 m bias correlated over 30 s, ~0.5 m in 10 s)."""

    def __init__(self, sc, rate):
        self.sc, self.rate, self.stop = sc, rate, False
        sc.be.clock.start_thread(self._loop, name='wandering fix')

    def _loop(self):
        ual, clock = self.sc.ual, self.sc.be.clock
        while not self.stop and not ual.pump:
            clock.sleep(0.02)
        t0 = clock.now()
        while not self.stop:
            with ual.lock:
                ual.gnss_offset = self.rate * (clock.now() - t0) * np.ones(3)
            clock.sleep(0.02)


def test_realistic_ugv_a_fire_put_out_is_judged_out_while_its_gnss_fix_wanders(scenes):
    """Realistic benchmark on 6b5ecb7: the UGV put out its ground-floor fire on its first tank in 8 of 8 runs,
    but in 6 it reported 'the tank ran dry before 6 cold answers in a row (0 so far)': standing still while
    its fix wandered (its controller holds no position at rest), it was 'off its watering pose' by GNSS and no
    cold answer counted; the fire stayed active for top-up trips. A UGV translates only when told: its
    heading says whether it still looks at the fire."""
    sc = UgvScene(hot_until=1.0)
    try:
        fire = FadingFire(sc, need=1.2, start_water=2.0, heat=50.0)
        sc.threads = (WanderingFix(sc, 0.06),)
        s = sc.extinguish(timeout=60)
        assert s.status == 'succeeded' and s.result.extinguished, s.result.message
        assert fire.progress() >= 1.0, f'judged out at {fire.progress():.3f} of its water'
    finally:
        sc.close()


class JetCooledFire(FadingFire):
    """A fire whose surface the jet cools: under water it reads `hidden` of its untouched heat colder than it
    is (at its wall's level well before it is out); once the water stops it shows the heat it still has."""

    def __init__(self, sc, hidden, **kw):
        self.hidden = hidden
        super().__init__(sc, **kw)

    def contrast(self):
        left = self.heat * max(0.0, 1.0 - self.progress())
        return max(0.0, left - self.hidden * self.heat) if self.sc.ual.pump else left


def test_a_fire_that_reads_cold_only_under_the_jet_is_watered_again_when_it_shows_hot_without_it(scenes):
    """Confirmed with the pump off, a fire still burning shows its heat again (firefighters watch for it
    once the water stops) and gets water until it is out. Before, the cold answers were counted under the
    jet: this fire (a third of its heat hidden by the water) was judged out at ~97 % of its water."""
    sc = scenes(hot_until=1.0)
    fire = JetCooledFire(sc, hidden=0.3, need=8.0, start_water=12.0, heat=50.0)
    s = sc.extinguish(timeout=90)
    assert fire.progress() >= 1.0 or not s.result.extinguished, \
        f'judged out at {fire.progress():.3f} of its water: {s.result.message}'
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message


def test_with_a_cold_threshold_at_the_detectors_contrast_the_same_fire_is_judged_out_too_early(scenes):
    """The test above can fail: judged cold about where the detector loses the fire (out_contrast 30 degC),
    the soak and the cold check end before the fire had its water, as with the detector's silence before."""
    sc = scenes(hot_until=1.0, params={'out_contrast': 30.0})
    fire = FadingFire(sc, need=10.0, start_water=14.0, heat=100.0, seen_share=0.45)
    s = sc.extinguish(timeout=60)
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert fire.progress() < 1.0


def test_a_fire_still_warm_on_a_noisy_sun_heated_wall_is_never_judged_out(scenes):
    """Water that never reaches the fire (it keeps 4 degC over its wall: 52 degC, 8 degC warmer on one side
    of the frame, the camera 2 degC off, pixel noise 1 degC): the detector lost it long ago, the raw image
    still sees it: the tank runs dry and it is left for a top-up, never reported out."""
    sc = scenes(hot_until=1.0)
    FadingFire(sc, need=2.0, start_water=4.0, wall=52.0, gradient=8.0, offset=2.0, noise=1.0,
               missing_at_least=4.0 / 60.0)
    s = sc.extinguish()
    assert s.status == 'succeeded' and not s.result.extinguished, s.result.message
    assert 'left for a top-up' in s.result.message
    assert sc.statuses == []


def test_a_nearly_full_fire_the_detector_does_not_report_is_topped_up_until_it_reads_at_its_walls_level(scenes):
    """Realistic benchmark on ed77bf3 (seeds 101, 102, 108): fires left at 95-97 % by a tank that ran dry were
    never finished, every top-up aborting as "not seen hot" (under the detector's contrast test). The raw image
    sees it 16 degC over its wall: it is locked, watered until it reads at the wall's level, and judged out
    only once it had its water."""
    sc = scenes(hot_until=0.0)
    fire = FadingFire(sc, need=2.0, start_water=4.0, heat=16.0, seen_share=2.0)
    s = sc.extinguish()
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert fire.progress() >= 1.0, f'judged out at {fire.progress():.3f} of its water'


def test_a_sun_heated_walls_slope_is_not_a_fire_for_a_top_up(scenes):
    """No fire, a wall 12 degC warmer on one side of the frame, noise 1 degC: nothing is locked, the top-up
    aborts as "not seen hot" and nothing is judged out."""
    sc = scenes(hot_until=0.0)
    FadingFire(sc, need=1.0, start_water=2.0, heat=0.0, seen_share=2.0, wall=50.0, gradient=12.0, noise=1.0)
    s = sc.extinguish()
    assert s.status == 'aborted' and 'not seen hot from the watering pose' in s.result.message, s.result.message
    assert sc.statuses == []


class DriftingFire:
    """A fire that water reaches only while the UAV's heading is within 2 deg of it: `need` L put in then; a raw
    contrast to its wall of `heat` deg C untouched, fading with the water in; the detector reports it while that
    contrast is over `seen_share` of its heat. Once the detector has lost it, the fire's bearing from the UAV
    moves to `drift_deg` (the UAV pushed sideways by the drift of its GNSS error) and the raw image shows it
    there (its pixel column by the camera's 33 deg field of view)."""

    def __init__(self, sc, need, start_water, heat=60.0, seen_share=0.45, drift_deg=8.0):
        self.sc, self.need, self.heat, self.seen_share = sc, need, heat, seen_share
        self.drift = math.radians(drift_deg)
        self.received, self.last_water, self.lost = 0.0, start_water, False
        sc.ual.water = start_water
        rng = np.random.default_rng(5)
        focal = 16.0 / math.tan(math.radians(16.5))
        sc.hot = lambda: self.contrast() > seen_share * heat
        sc.ual.thermal = lambda: fake_thermal.fire_frame(
            self.contrast(), rng=rng, centre=(15.5, 15.5 - focal * math.tan(self.bearing() - sc.ual.yaw)))

    def bearing(self):
        return self.drift if self.lost else 0.0

    def contrast(self):
        water = self.sc.ual.water
        if abs(math.remainder(self.sc.ual.yaw - self.bearing(), 2 * math.pi)) < math.radians(2.0):
            self.received += max(0.0, self.last_water - water)
        self.last_water = water
        c = self.heat * max(0.0, 1.0 - self.received / self.need)
        self.lost = self.lost or c <= self.seen_share * self.heat
        return c


def test_realistic_101_103_108_a_frozen_aim_follows_the_warm_area_of_the_raw_image_onto_a_fire_it_drifted_off(
        scenes):
    """Realistic benchmark on 6b5ecb7: once the detector lost the fire the aim was frozen, the UAV drifted with
    its GNSS error, and tank after tank missed a fire the raw image still saw 15-25 degC over its wall (left at
    0.27, 0.88, 0.67). Now the frozen heading turns onto the raw image's warm area: the fire gets its water."""
    sc = scenes(hot_until=1.0)
    fire = DriftingFire(sc, need=4.0, start_water=8.0)
    s = sc.extinguish(timeout=60)
    assert fire.lost
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message
    assert fire.received >= fire.need, f'judged out after {fire.received:.2f} L of {fire.need:.2f}'


def test_a_frozen_aim_without_the_raw_image_steering_leaves_a_fire_it_drifted_off_for_a_top_up(scenes):
    """The test above can fail: with the raw image unable to turn the frozen aim (a field of view so narrow that
    the warm area's bearing is within the aim's tolerance), the water misses and the tank runs dry."""
    sc = scenes(hot_until=1.0, params={'forward_camera_fov': 0.5})
    fire = DriftingFire(sc, need=4.0, start_water=8.0)
    s = sc.extinguish(timeout=60)
    assert fire.lost
    assert s.status == 'succeeded' and not s.result.extinguished, s.result.message
    assert fire.received < fire.need


def test_the_frozen_aim_never_turns_on_a_fire_cut_by_the_frames_edge(scenes):
    """The detector lost the fire (aim frozen) and the raw frames show a warm area cut by the frame's left
    edge around no hole: its centroid says nothing sure of where the fire's centre is (from the watering
    distance it may lie on the wrong side of the image centre: ual_sim's realistic world, 1.0 m from the wall,
    a fire 6 deg left read 3 deg right), so the heading stays. Before: it turned 0.72 rad after it."""
    sc = scenes(hot_until=1.0)
    rng = np.random.default_rng(6)
    sc.ual.thermal = lambda: fake_thermal.fire_frame(60.0 if sc.hot() else 30.0, rng=rng,
                                                     centre=(15.5, 15.5 if sc.hot() else -1.0))
    yaws, start_pump = [], sc.be.handlers['actuators_system/start_pump']
    sc.be.handlers['actuators_system/start_pump'] = lambda r: yaws.append(sc.ual.yaw) or start_pump(r)

    class Heading:                     # the UAV's heading while the pump runs
        stop, turned = False, 0.0

        def __init__(self):
            sc.be.clock.start_thread(self.loop, name='heading')

        def loop(self):
            while not self.stop:
                if sc.ual.pump and yaws:
                    self.turned = max(self.turned, abs(math.remainder(sc.ual.yaw - yaws[0], 2 * math.pi)))
                sc.be.clock.sleep(0.05)
    heading = Heading()
    sc.threads = (heading,)
    sc.extinguish()
    assert yaws, 'never pumped'
    assert heading.turned < 0.05, f'the frozen aim turned {heading.turned:.2f} rad onto a fire cut by the edge'


@pytest.mark.parametrize('bias', [(0.0, -0.9, 0.0), (0.0, 0.9, 0.0), (0.0, 0.0, 0.75), (0.0, 0.0, 1.1)])
def test_realistic_103_a_fire_out_of_the_view_from_the_watering_pose_is_looked_for_around_it(scenes, bias):
    """Realistic seed 103 (fd8 run, run 103): UAV 2, sent to top up in1_e, reached the watering
    pose its GNSS fix and the fire's track put 1.5 m in front of it, read the fire cold there twice (detector
    and raw image) and pumped 1.27 L beside it while it was burning at 0 % (no lock on a warm area: it was not
    in the 33 deg view). The track's and the robot's GNSS errors (0.5 m per axis each, 0.4 m in height)
    differ by more than the view's half-width plus the ring of flames at 1.5 m (~0.85 m) in a fair share of
    approaches. Now the robot looks beside and above and below the heading for a warm area before it gives
    the fire a top-up or gives up, and waters it from the heading it finds it at. Before: the top-up went
    beside it and the goal failed, the fire received nothing. A height 1.1 m off (explore + GNSS-denied seed 109
    on 61430b6: in1_w's track 0.78 m above the fire, the GNSS height of the robot that saw it, and the top-up
    robot's own vertical error besides) is found by the looks twice as far up and down."""
    sc = scenes()
    sc.ual.gnss_bias = np.array(bias)
    cam = LevelCamera(sc)
    sc.threads = (cam,)
    s = sc.extinguish(timeout=60)
    assert cam.received >= cam.need, f'{cam.received:.2f} s of water in of {cam.need:.2f}: {s.result.message}'
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message


class Wobble:
    """Gusts fought by the UAV's position hold (ual_sim's wind near the building's first floor: ~0.27 m std,
    changing within a second): its fix (here: only the published pose, the truth stays at the set-point) reads
    a fresh offset of `std` m sideways every `period` s; the UAL holds its set-point all the while."""

    def __init__(self, sc, std=0.2, period=0.3):
        self.sc, self.std, self.period, self.stop = sc, std, period, False
        self.rng = np.random.default_rng(4)
        sc.be.clock.start_thread(self._loop, name='wobble')

    def _loop(self):
        ual, clock = self.sc.ual, self.sc.be.clock
        while not self.stop:
            with ual.lock:
                ual.gnss_offset = np.array([*np.clip(self.rng.normal(0.0, self.std, 2), -0.4, 0.4), 0.0])
            clock.sleep(self.period)


def test_realistic_104_the_aims_turns_keep_the_uavs_set_point_while_gusts_push_it_about(scenes):
    """Realistic seed 104 (fd8 run with its bag, run 104): on floor 1 the gusts push a UAV
    +-0.2-0.3 m about its set-point within a second; every turn of the aim (and every re-sent height of a
    frozen aim) sent the fix of that moment as the new set-point, so that the set-point walked with the gusts:
    in1_w's first pour, 14 turns, the UAV 0.6 m off where it started, the jet 0.2-0.4 m beside the hole for
    much of it (55 % of the fire for a tank); seed 108: 'reads cold, not counted: 0.96 m (by its fix) off the
    watering pose' as the fire went out, so it was not judged out and two more tanks went to it. Now a UAV's
    turns keep the set-point it holds (moved only by a wall back-off): the jet stays on the fire."""
    sc = scenes()
    sc.ual.water = 3.0
    cam = LevelCamera(sc, need=3.0, hit=0.1)
    drift = SideDrift(sc, rate=0.03, limit=0.2)       # the aim turns after the GNSS error's drift
    wobble = Wobble(sc)
    sc.threads = (cam, drift, wobble)
    goals = []                                          # the x, y set-points sent, and whether the pump ran
    go_to = sc.be.handlers['ual/go_to_waypoint']
    sc.be.handlers['ual/go_to_waypoint'] = lambda r: goals.append(
        ((r.waypoint.pose.position.x, r.waypoint.pose.position.y), sc.ual.pump)) or go_to(r)
    s = sc.extinguish(timeout=60)
    first = next(i for i, (_, pumping) in enumerate(goals) if pumping)
    held = goals[first - 1][0]                          # the set-point when the water started
    assert drift.started and first > 0
    walk = max(math.dist(g, held) for g, pumping in goals[first:] if pumping)
    assert walk < 0.05, f'the set-point walked {walk:.2f} m with the gusts while pumping'
    assert cam.received >= cam.need, f'{cam.received:.2f} s of water in of {cam.need:.2f}: {s.result.message}'
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message


def test_realistic_103_a_uav_its_gnss_drift_takes_towards_the_wall_keeps_its_watering_distance(scenes):
    """Realistic seed 103 (fd8 run with its bag, run 103_after): in1_e's first pour, the GNSS error
    drifted 0.7 m along the wall's normal and took the UAV from 1.5 to 1.0-1.2 m from the wall, where the ring of
    flames fills the view and the image no longer shows the hole whole: the aim no longer followed it, the jet
    went 0.2-0.3 m beside and below the hole and the fire stayed at 71 % while the tank ran dry (the wall
    back-off acts only within ~min_wall_clearance, 1.0 m). Now the set-point steps back along the heading to
    ~indoor_fire_distance from the wall the laser sees ahead once it is 0.25 m nearer. Before: 1.1 m to the end."""
    from laser_world import LaserScene
    sc = scenes(hot_until=30.0)
    sc.ual.water = 8.0
    laser = LaserScene(sc.be, sc.ual, noisy=False)
    laser.boxes = [(4.05, -5.0, 4.25, 5.0)]             # the fire's wall (FIRE at x 4.0), 1.55 m ahead
    drift = SideDrift(sc, rate=-0.2, limit=0.4, axis=0)   # 103: -0.46 -> +0.23 m along the normal in 7 s
    sc.threads = (laser, drift)
    sc.be.clock.sleep(0.5)
    seen = []
    sc.be.clock.start_thread(lambda: [seen.append((drift.started, 4.05 - sc.ual.pos[0])) or sc.be.clock.sleep(0.1)
                                      for _ in range(150)], name='distance')
    sc.extinguish(timeout=60)
    late = [d for started, d in seen[-30:] if started]
    assert drift.started and late, 'the drift never started'
    assert min(late) >= 1.3, f'{min(late):.2f} m from the wall while watering, after the drift'


def test_realistic_105_the_look_around_never_turns_onto_a_faint_warm_area_beside_the_view(scenes):
    """Realistic seed 105 (A's run on ff4b066): a top-up of a fire at 98 % (too faint for the raw image) looked
    around, turned 43 deg onto a warm area 5 degC over its wall (a wall's feature, not the fire), locked it as
    hot and poured its whole tank there. A warm area found beside the view counts only when it stands clearly
    over its wall (LOOK_MIN_RISE x ~out_contrast); the top-up then goes where the watering pose faces. Before:
    the UAV turned onto it (0.5 rad)."""
    sc = scenes(hot_until=0.0)
    rng = np.random.default_rng(7)
    yaw0 = []

    def frame():                         # a faint warm area 0.5 rad right of the first heading, nothing else
        if not yaw0:
            yaw0.append(sc.ual.yaw)
        return frame_at(5.0, -0.5 - (sc.ual.yaw - yaw0[0]), 0.0, rng)
    sc.ual.thermal = frame
    sc.extinguish(timeout=60)
    assert yaw0 and abs(math.remainder(sc.ual.yaw - yaw0[0], 2 * math.pi)) < 0.05, \
        f'turned {sc.ual.yaw - yaw0[0]:+.2f} rad onto a faint warm area'


@pytest.mark.parametrize('window', ['window', 'jamb beside the bearing', None])
def test_seed_106_a_warm_area_seen_through_a_window_beside_the_fire_is_not_taken_for_it(scenes, window):
    """Explore + GNSS-denied seed 106: in1_w, 98 % out and too faint to see, stands beside a window; four
    top-ups each looked around, took the warmest area, 33 deg off the heading and 29-37 degC over its wall
    (the sun-heated outside, through the window), and poured their whole tank there. The laser places a
    warm area: along its bearing a window (no return) is not the fire; a wall 0.85 m beside the fire's
    estimate may be (its GNSS error: realistic seed 103), and the robot turns onto it. Seed 109 on fb42812:
    the window's jamb 0.1 m beside the bearing, within the corridor the laser places it by, the outside seen
    past it: the bearing itself must meet the surface (before: turned onto it, a tank poured outside twice)."""
    from laser_world import LaserScene
    sc = scenes(hot_until=0.0)
    laser = LaserScene(sc.be, sc.ual, noisy=False)
    # the fire's wall (x 4.05), a window at y -2.0..-0.5 in it, or -2.0..-0.75 (the bearing crosses the wall at
    # y -0.85: 0.1 m past the jamb), or none
    jamb = {'window': -0.5, 'jamb beside the bearing': -0.75}.get(window)
    wall = [(4.05, jamb, 4.25, 5.0), (4.05, -5.0, 4.25, -2.0)] if window else [(4.05, -5.0, 4.25, 5.0)]
    laser.boxes = wall
    sc.threads = (laser,)
    sc.be.clock.sleep(0.5)
    rng = np.random.default_rng(7)
    yaw0 = []

    def frame():                           # a strong warm area 0.5 rad right of the first heading
        if not yaw0:
            yaw0.append(sc.ual.yaw)
        return frame_at(30.0, -0.5 - (sc.ual.yaw - yaw0[0]), 0.0, rng)
    sc.ual.thermal = frame
    sc.extinguish(timeout=60)
    turned = math.remainder(sc.ual.yaw - yaw0[0], 2 * math.pi)
    if window:
        assert abs(turned) < 0.05, f'turned {turned:+.2f} rad onto a warm area seen through the window'
    else:
        assert turned < -0.35, f'turned {turned:+.2f} rad: not onto the warm area on the fire\'s wall'


class DriftsOutOfView:
    """The fire seen hot and watered, then (after `after` s of pumping) out of the camera's view `offset` rad to
    the left, as when the aim frozen on it drifts off: in view it is a ring of flames 25 degC over its wall
    (the detector reports it), out of view the frame is bare wall (every area at the wall's level)."""

    def __init__(self, sc, after=1.5, offset=0.5):
        self.sc, self.after, self.offset, self.stop = sc, after, offset, False
        self.drifted = False
        rng = np.random.default_rng(11)
        self.half_view = math.radians(33.0) / 2
        sc.ual.thermal = lambda: (fake_thermal.ring_frame(25.0, (15.5, 15.5 - FOCAL * math.tan(self.bearing())),
                                                          rng=rng)
                                  if self.in_view() else fake_thermal.fire_frame(0.0, wall=35.0, rng=rng))
        sc.be.handlers['thermal_detection/fire_detected'] = lambda r: CheckFireResponse(fire_detected=self.in_view())
        sc.be.clock.start_thread(self._loop, name='drift')

    def bearing(self):
        u = self.sc.ual
        with u.lock:
            pos, yaw = u.pos.copy(), u.yaw
        rel = math.atan2(FIRE[1] - pos[1], FIRE[0] - pos[0]) - yaw + (self.offset if self.drifted else 0.0)
        return math.remainder(rel, 2 * math.pi)

    def in_view(self):
        return abs(self.bearing()) < self.half_view

    def _loop(self):
        be, since = self.sc.be, None
        while not self.stop:
            if self.sc.ual.pump and since is None:
                since = be.clock.now()
            if since is not None and be.clock.now() - since >= self.after:
                self.drifted = True
            be.clock.sleep(0.05)


def test_realistic_107_a_fire_that_left_the_view_is_looked_for_beside_it_before_it_is_judged_out(scenes):
    """Realistic seed 107 (52c0d45): a top-up's aim drifted off the fire, the whole view read at the wall's level
    and the fire, 0.87 full and 26 degC over its wall beside the view, was reported out. After the cold answers
    the robot looks LOOK_TURN to either side: the ring of flames there says it still burns; the goal succeeds
    with the fire not judged out (left active). Before: extinguished."""
    sc = scenes()
    drift = DriftsOutOfView(sc)
    sc.threads = (drift,)
    s = sc.extinguish(timeout=60)
    assert drift.drifted
    assert s.status == 'succeeded' and not s.result.extinguished, s.result.message
    assert 'beside the watering pose after the cold answers' in s.result.message, s.result.message
    assert sc.statuses == []


def test_a_fire_put_out_in_view_is_still_judged_out_after_the_look_beside_it(scenes):
    """The look beside a fire that is out finds nothing (bare walls both sides): out, as before."""
    sc = scenes()
    fire = FireModel(sc, need=1.0)
    sc.threads = (fire,)
    s = sc.extinguish(timeout=60)
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message


class RingFillsTheView(LevelCamera):
    """The detector's contrast test against the frame's median: from the watering distance a fire straight
    ahead fills the view with its ring of flames and the detector no longer reports it; off the optical axis
    (more than 0.1 rad) it does. The raw image shows it wherever it is in the view."""

    def hot(self):
        return super().hot() and abs(self.view()[1]) > 0.1

    def frame(self, rng):
        d, bearing, rise = self.view()
        return frame_at(60.0 if self.in_image() and self.received < self.need else 0.0, bearing,
                        math.atan2(rise, d), rng)


def test_seed_109_a_fire_the_detector_loses_once_aimed_at_is_watered_on_the_raw_image(scenes):
    """Explore + GNSS-denied seed 109 on e45b72d: a top-up robot saw in1_w (69 % out) with the detector in a
    look 29 deg aside, turned onto it, and there the ring of flames filled its view: the detector's test
    against the frame's median failed and the goal aborted 'hot before aiming at its hot spot, cold after; no
    water spent', three times; the fire was doubted and left burning. Just aimed at a fire the detector
    reported, the raw image's steady warm area says hot: watered until out. Here the watering pose faces
    0.15 rad beside the fire (the track off): reported at once, aimed at, then silent."""
    sc = scenes()
    cam = RingFillsTheView(sc)
    sc.threads = (cam,)
    track = sc.agent.fire(7).pose.pose.position
    track.y = FIRE[1] + 1.5 * math.tan(0.15)                   # the watering pose faces 0.15 rad beside it
    s = sc.extinguish(timeout=60)
    assert 'hot before aiming' not in s.result.message, s.result.message
    assert cam.received >= cam.need, f'{cam.received:.2f} s of water in of {cam.need:.2f}: {s.result.message}'
    assert s.status == 'succeeded' and s.result.extinguished, s.result.message


class PumpHeights:
    """The UAV's true heights while its pump runs."""

    def __init__(self, sc):
        self.sc, self.heights, self.stop = sc, [], False
        sc.be.clock.start_thread(self._loop, name='pump heights')

    def _loop(self):
        while not self.stop:
            if self.sc.ual.pump:
                self.heights.append(float(self.sc.ual.pos[2]))
            self.sc.be.clock.sleep(0.05)


@pytest.mark.parametrize('bias_z', [0.45, -0.4])
def test_realistic_101_a_blind_top_up_waters_at_the_tracks_true_height_whatever_its_gnss_error(scenes, bias_z):
    """A track's height is a true one (the detectors place fires at the finding UAV's true height): a UAV
    topping up a fire that reads cold (nothing to steer on) flies to it at its own true height, not at the
    GNSS one (realistic seed 101 at rtf 4: the top-up's jet 0.36 m under the pour that had put 1.1 L in,
    none of its water in, the fire left at 99.4 %)."""
    sc = scenes(hot_until=0.0)
    sc.ual.gnss_bias = np.array([0.0, 0.0, bias_z])
    sc.be.clock.sleep(2.0)                                   # the altimeter's estimate of the error settles
    pump = PumpHeights(sc)
    sc.threads = (pump,)
    s = sc.extinguish(timeout=60)
    assert 'not seen hot from the watering pose' in s.result.message, s.result.message
    assert pump.heights, 'no water pumped'
    assert abs(float(np.median(pump.heights)) - FIRE[2]) < 0.12, (bias_z, np.median(pump.heights))
