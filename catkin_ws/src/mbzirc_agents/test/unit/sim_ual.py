"""A closed loop without ROS: the real agent and its extinguish_indoor_fire task against ual_sim's Simulation
(its renderer, GNSS bias, gusts, laser, altimeter and jet, under a named uncertainty profile) and the fire
detector's own core (fire_detector.detector.FireDetector), on the FakeBackend's simulated clock.

Why: the scripted cameras of test_indoor_water.py test rules; where the jet lands relative to the hole and how
many litres go in under the trial's unknowns only the simulator's truth says (issue 17: 2-5 full tanks poured on
one indoor fire). The simulator is the referee here: the agent reads only what its sensors publish.

SimUal stands in for the UAL, the actuators, the sensors and the thermal detector of one UAV of the world;
`pour(seed, ...)` places it in front of an indoor fire with a track of it and runs one ExtinguishIndoorFire goal
on one tank, returning the litres pumped and put into the fire, the verdict and a per-tick record.
"""
import math

import numpy as np
from geometry_msgs.msg import PoseStamped
from mbzirc_comm_objs.msg import ExtinguishIndoorFireGoal, Object, ObjectDetection, ObjectDetectionList, ObjectList
from mbzirc_comm_objs.msg import ThermalImage
from mbzirc_comm_objs.srv import CheckFireResponse
from sensor_msgs.msg import LaserScan, Range
from std_msgs.msg import Float32
from std_srvs.srv import TriggerResponse
from uav_abstraction_layer.msg import State
from uav_abstraction_layer.srv import GoToWaypointResponse

import fake_thermal
from fake_backend import FakeBackend
from fake_ual import FakeUal, start_agent, stop_agent
from mbzirc_agents import constants as C

DT = 0.05            # s of one simulation step
THERMAL_PERIOD = 0.1  # s between thermal frames (the detector processes each)
SCAN_PERIOD = 0.1
ALT_PERIOD = 0.05


class SimUal(FakeUal):
    """FakeUal's services and topics, served by robot `rid` of a ual_sim Simulation (true pose, GNSS-biased
    reported pose, its jet), with the thermal detector run on its forward camera's frames."""

    def __init__(self, backend, sim, rid):
        from fire_detector.detector import DetectorConfig, FireDetector
        from ual_sim.thermal import FORWARD
        self.sim, self.rid, self.r = sim, rid, sim.robots[rid]
        self.detector = FireDetector(DetectorConfig(camera_config='FORWARD'))
        self.forward = FORWARD
        self.ticks = []               # (sim time, true pos, yaw, pump on, jet end, fire index, share)
        self.fire_index = None        # the fire whose hole the record measures the jet against
        self._times = {'thermal': -np.inf, 'scan': -np.inf, 'alt': -np.inf}
        super().__init__(backend, pos=self.r.pos, speedup=1.0)
        backend.handlers['thermal_detection/fire_detected'] = \
            lambda req: CheckFireResponse(fire_detected=self.detector.fire_detected)

    # ---- UAL commands
    def take_off(self, req):
        raise AssertionError('the closed loop starts in the air')

    def land(self, req):
        raise AssertionError('the closed loop does not land')

    def go_to(self, req):
        p, q = req.waypoint.pose.position, req.waypoint.pose.orientation
        with self.sim.lock:
            self.r.go_to(p.x, p.y, p.z, math.atan2(2 * q.w * q.z, 1 - 2 * q.z * q.z))
        self.waypoints.append(((p.x, p.y, p.z), None))
        return GoToWaypointResponse()

    def _pump(self, on):
        with self.sim.lock:
            (self.sim.start_pump if on else self.sim.stop_pump)(self.rid)
        self.pump = on
        return TriggerResponse(success=True, message='')

    # ---- the loop: step the world, publish what the sensors see
    def _loop(self):
        subs = self.be.subs
        while not self.stop:
            now = self.be.clock.now()
            with self.sim.lock:
                self.sim.step(DT)
                r = self.r
                jet = self.sim.jets.get(self.rid)
                self.ticks.append((now, r.pos.copy(), r.yaw, r.pump_on, None if jet is None else jet.end.copy(),
                                   None if jet is None else jet.fire, 0.0 if jet is None else jet.share))
                rep = self.sim.reported_pose(r)
                self.pos, self.yaw, self.water = r.pos.copy(), r.yaw, r.water
                state = State.FLYING_AUTO if r.flying else State.LANDED_ARMED
                alt = self.sim.altimeter(r) if now - self._times['alt'] >= ALT_PERIOD - 1e-9 else None
                scan = self.sim.laser(r) if now - self._times['scan'] >= SCAN_PERIOD - 1e-9 else None
                frame = (self.sim.thermal_frame(r, self.forward)
                         if now - self._times['thermal'] >= THERMAL_PERIOD - 1e-9 else None)
            msg = PoseStamped()
            msg.header.frame_id = 'arena'
            msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = rep[:3]
            msg.pose.orientation.z, msg.pose.orientation.w = math.sin(rep[3] / 2), math.cos(rep[3] / 2)
            for topic, m in (('ual/pose', msg), ('ual/state', State(state=state)),
                             ('actuators_system/water_level', Float32(data=self.water))):
                if topic in subs:
                    subs[topic](m)
            if alt is not None:
                self._times['alt'] = now
                if 'altimeter' in subs:
                    subs['altimeter'](Range(min_range=0.05, max_range=40.0, range=float(alt)))
            if scan is not None:
                self._times['scan'] = now
                if 'scan' in subs:
                    inc = 2.0 * math.pi / len(scan)
                    subs['scan'](LaserScan(angle_min=-math.pi, angle_increment=inc, range_min=0.15,
                                           range_max=25.0, ranges=list(scan)))
            if frame is not None:
                self._times['thermal'] = now
                self._thermal(frame, rep, scan)
            self.be.clock.sleep(DT)

    def _thermal(self, frame, rep, scan):
        """The raw frame to the agent, and the detector's answer (and detection) on it."""
        from fire_detector.geometry import front_laser_range
        fake_thermal.publish(self.be, frame)
        ranges = self.sim.laser(self.r) if scan is None else scan
        front = front_laser_range(ranges, -math.pi, 2.0 * math.pi / len(ranges), 0.15, 25.0, 5.0)
        result = self.detector.process(frame.ravel(), tuple(rep[:3]), float(rep[3]), front)
        cb = self.be.subs.get('sensed_objects')
        if result.fire is None or cb is None:
            return
        import rospy
        det = ObjectDetection(type=C.TYPE_FIRE)
        det.header.stamp = rospy.Time.from_sec(self.be.clock.now())
        det.pose.pose.position.x, det.pose.pose.position.y, det.pose.pose.position.z = result.fire.position
        rel = result.fire.relative_position
        det.relative_position.x, det.relative_position.y, det.relative_position.z = rel
        det.image_detection = ThermalImage(camera_direction=self.detector.config.camera_direction)
        cb(ObjectDetectionList(objects=[det]))

    # ---- the record
    def misses(self):
        """Per pumping tick: (sim time, m the jet's end lies from the hole centre in the wall's plane, share)."""
        out = []
        c = self.sim.fires.pos[self.fire_index]
        n = self.sim.fires.normal[self.fire_index]
        for t, _pos, _yaw, pump, end, _fire, share in self.ticks:
            if pump and end is not None:
                rel = end - c
                out.append((t, float(np.linalg.norm(rel - (rel @ n) * n)), share))
        return out


def indoor_fire(sim, holder_id):
    """The index of the indoor holder `holder_id` in sim's fire set, made active."""
    for i, f in enumerate(sim.fires.fires):
        if f.holder.id == holder_id:
            f.active = True
            return i
    raise KeyError(holder_id)


def pour(seed, holder='in1_e', need=None, params=None, start_distance=2.5, profile_name='realistic',
         timeout=120.0, litres=None, track_from=None, progress=0.0):
    """One ExtinguishIndoorFire goal on one tank against ual_sim's world under `profile_name`, seed `seed`:
    a water UAV placed start_distance m in front of indoor fire `holder` (at its height, facing it), its track
    at the fire as its own GNSS frame puts it horizontally (truth + the UAV's bias then), at its true height
    (track_from: another robot's id, the track placed with that robot's bias instead, as when one robot found
    the fire and another waters it).
    need: litres the fire needs (None:
    the seed's draw; a large value measures the whole tank). litres: the tank (None: full). progress: the share
    of its need the fire already holds (a top-up of a fire left nearly out by a tank that ran dry).
    Returns a dict: pumped, into (L into the fire), progress, status, extinguished, message, misses, ual."""
    from ual_sim.sim import Simulation
    from ual_sim.uncertainty import profile, with_gnss_denied_indoors
    from ual_sim.world import load_world
    from mbzirc_agents.uav_agent import UavAgent
    world = load_world()
    # the fix indoors too: a pour is measured on the UAL's pose (no SLAM here), with the GNSS error of the
    # profile; a pose without GNSS indoors is indoor_localization's (its own tests)
    sim = Simulation(world, seed=seed, uncertainty=with_gnss_denied_indoors(profile(world.uncertainty, profile_name),
                                                                            False))
    i = indoor_fire(sim, holder)
    fire = sim.fires.fires[i]
    if need is not None:
        fire.litres_needed = need
    fire.litres = progress * fire.litres_needed
    rid = next(rid for rid, r in sim.robots.items() if r.is_uav and r.water > 0)
    r = sim.robots[rid]
    c, n = sim.fires.pos[i], sim.fires.normal[i]
    r.state, r.mode = State.FLYING_AUTO, 'idle'
    r.pos = c + n * start_distance
    r.yaw = math.atan2(-n[1], -n[0])
    r.goal, r.goal_yaw = r.pos.copy(), r.yaw
    if litres is not None:
        r.water = litres
    be = FakeBackend()
    ual = SimUal(be, sim, rid)
    ual.fire_index = i
    agent = start_agent(UavAgent('2', be, {'region_timeout': 5.0, **(params or {})}), be)
    try:
        finder = rid if track_from is None else track_from
        err = sim.uncertainty.gnss_fix(finder) if sim.uncertainty is not None else np.zeros(3)
        # horizontally the finder's GNSS error; its height the finder's true one (the detectors place fires
        # at the height the finder's altimeter corrects, UavAgent._detectors_pose)
        track = c + np.array([err[0], err[1], 0.0])
        o = Object(id=7, type=C.TYPE_FIRE, sub_type=C.SUBTYPE_INDOOR, status=C.STATUS_ACTIVE, num_updates=50)
        o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z = track
        o.pose.covariance = [0.0] * 36
        o.pose.covariance[0] = o.pose.covariance[7] = o.pose.covariance[14] = 0.2 ** 2
        be.subs['/estimated_objects'](ObjectList(objects=[o]))
        be.clock.sleep(1.0)                          # its first frames and scans
        tank = r.water
        s = be.servers['extinguish_indoor_fire_action']
        s.send(ExtinguishIndoorFireGoal(fire_id=7))
        status = s.wait(timeout)
        res = s.result
        return {'pumped': tank - r.water, 'into': fire.litres - progress * fire.litres_needed, 'progress': fire.progress, 'status': status,
                'extinguished': bool(res.extinguished) if res is not None else False,
                'message': res.message if res is not None else s.text, 'misses': ual.misses(), 'ual': ual,
                'need': fire.litres_needed, 'agent': agent, 'backend': be}
    finally:
        stop_agent(agent, ual, be)
