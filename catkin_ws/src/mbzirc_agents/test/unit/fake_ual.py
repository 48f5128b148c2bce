"""A kinematic UAV behind the FakeBackend: the UAL services and topics the agents use, sped up.

Why: the tasks' logic (regions, waiting, preemption, goal checks) is tested in a second without ROS;
the rostests check the same against ual_sim. It runs on the backend's simulated clock (sim_clock.py).
"""
import math
import threading

import numpy as np
import rospy
from geometry_msgs.msg import PoseStamped
from sensor_msgs.msg import Range
from mbzirc_comm_objs.srv import AskForRegionResponse, FreeRegionsResponse
from std_msgs.msg import Float32
from std_srvs.srv import TriggerResponse
from uav_abstraction_layer.msg import State
from uav_abstraction_layer.srv import GoToWaypointResponse, LandResponse, TakeOffResponse

from shared_regions_manager.core import RegionManager

import fake_thermal


class FakeUal:
    def __init__(self, backend, pos=(0.0, 0.0, 0.0), speedup=4.0, regions=None):
        self.be = backend
        self.pos = np.array(pos, float)
        self.gnss_offset = np.zeros(3)   # added to the published pose only (a GNSS jump)
        # GNSS error as the real UAL has it: added to the published pose AND the UAL flies its go-to set-points
        # in that frame (true set-point = command - bias, moving as the bias changes), as ual_sim does
        self.gnss_bias = np.zeros(3)
        self.altimeter = True            # publish `altimeter` (true height above the ground at z 0), 20 Hz
        self.altimeter_reading = None    # a fixed reading instead (NaN: an invalid one), when set
        self.min_flying_z = np.inf       # lowest true z while flying, not taking off (ground contact: <= 0)
        self.yaw = 0.0
        self.state = State.LANDED_DISARMED
        self.goal = None
        self.vel = None
        self.yaw_rate = 0.0              # of the latest velocity command (rad/s), followed with it
        self.vel_time = 0.0
        self.water = 2.0
        self.pump = False
        self.speedup = speedup
        self.regions = regions or RegionManager()
        self.waypoints = []
        self.follow_velocity = False     # opt-in: fly the agent's ual/set_velocity commands (0.3 s each)
        self.thermal = None              # opt-in: () -> a raw thermal frame (fake_thermal.py), sent at 10 Hz
        self._thermal_time = -np.inf
        self._vel_seen = 0
        self._alt_time = -np.inf
        self.lock = threading.Lock()
        h = backend.handlers
        h['ual/take_off'] = self.take_off
        h['ual/land'] = self.land
        h['ual/go_to_waypoint'] = self.go_to
        h['actuators_system/start_pump'] = lambda r: self._pump(True)
        h['actuators_system/stop_pump'] = lambda r: self._pump(False)
        h['/ask_for_region'] = lambda r: AskForRegionResponse(success=self.regions.ask(
            r.agent_id, r.label, (r.min_corner.point.x, r.min_corner.point.y, r.min_corner.point.z),
            (r.max_corner.point.x, r.max_corner.point.y, r.max_corner.point.z))[0])
        h['/free_regions'] = lambda r: FreeRegionsResponse(success=self.regions.free(r.agent_id, r.label, r.free_all)[0])
        self.stop = False
        self.thread = backend.clock.start_thread(self._loop, name='fake UAL')

    def _pump(self, on):
        self.pump = on
        return TriggerResponse(success=True, message='')

    def take_off(self, req):
        with self.lock:
            self.goal = (self.pos + [0, 0, req.height] + self.gnss_bias, self.yaw)
            self.state = State.TAKING_OFF
        return TakeOffResponse()

    def land(self, req):
        with self.lock:
            self.goal = (np.array([self.pos[0], self.pos[1], 0.0]) + self.gnss_bias, self.yaw)
            self.state = State.LANDING
        return LandResponse()

    def go_to(self, req):
        p, q = req.waypoint.pose.position, req.waypoint.pose.orientation
        with self.lock:
            if self.state not in (State.FLYING_AUTO, State.FLYING_MANUAL):
                return GoToWaypointResponse()
            self.goal = (np.array([p.x, p.y, p.z]), math.atan2(2 * q.w * q.z, 1 - 2 * q.z * q.z))
            self.vel = None
            self.waypoints.append(self.goal)
        return GoToWaypointResponse()

    def _velocity(self):
        """The latest ual/set_velocity command if it is new or under 0.3 s old (world m/s), else None."""
        msgs = self.be.pubs.get('ual/set_velocity') or []
        if len(msgs) != self._vel_seen:
            self._vel_seen = len(msgs)
            if msgs:
                t = msgs[-1].twist.linear
                self.vel, self.vel_time = np.array([t.x, t.y, t.z]), self.be.clock.now()
                self.yaw_rate = msgs[-1].twist.angular.z
        if self.vel is not None and self.be.clock.now() - self.vel_time < 0.3:
            return self.vel
        return None

    def _loop(self):
        dt = 0.02
        while not self.stop:
            v = self._velocity() if self.follow_velocity else None
            with self.lock:
                if v is not None and self.state in (State.FLYING_AUTO, State.FLYING_MANUAL):
                    self.goal = None
                    self.pos = self.pos + v * self.speedup * dt
                    self.yaw = math.atan2(math.sin(self.yaw + self.yaw_rate * self.speedup * dt),
                                          math.cos(self.yaw + self.yaw_rate * self.speedup * dt))
                if self.goal is not None and self.state not in (State.LANDED_DISARMED, State.LANDED_ARMED):
                    g, gy = self.goal                       # (landed, it stays put as the GNSS error moves)
                    g = g - self.gnss_bias                  # flown in the frame of the GNSS fix
                    if self.state == State.LANDING:
                        g[2] = 0.0                          # down to the ground, whatever the fix says
                    d = g - self.pos
                    n = np.linalg.norm(d)
                    step = 1.6 * self.speedup * dt
                    self.pos = g.copy() if n <= step else self.pos + d / n * step
                    self.yaw = gy
                    if n <= step:
                        if self.state == State.TAKING_OFF:
                            self.state = State.FLYING_AUTO
                        elif self.state == State.LANDING:
                            self.state = State.LANDED_DISARMED
                if self.pump and self.water > 0:
                    self.water = max(0.0, self.water - 0.2 * self.speedup * dt)
                if self.state in (State.FLYING_AUTO, State.FLYING_MANUAL):
                    self.min_flying_z = min(self.min_flying_z, self.pos[2])
                pos, yaw, state, water = self.pos + self.gnss_offset + self.gnss_bias, self.yaw, self.state, self.water
                height = self.pos[2] if self.altimeter_reading is None else self.altimeter_reading
            msg = PoseStamped()
            msg.header.frame_id = 'arena'
            msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = pos
            msg.pose.orientation.z, msg.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
            subs = self.be.subs
            if 'ual/pose' in subs:
                subs['ual/pose'](msg)
            if 'ual/state' in subs:
                subs['ual/state'](State(state=state))
            if 'actuators_system/water_level' in subs:
                subs['actuators_system/water_level'](Float32(data=water))
            now = self.be.clock.now()
            if self.altimeter and 'altimeter' in subs and now - self._alt_time >= 0.05 - 1e-9:
                self._alt_time = now
                m = Range(min_range=0.05, max_range=40.0)
                m.header.stamp = rospy.Time.from_sec(now)
                m.range = height if height >= 0.05 or not np.isfinite(height) else -np.inf
                subs['altimeter'](m)
            if self.thermal is not None and now - self._thermal_time >= 0.1 - 1e-9:
                self._thermal_time = now
                fake_thermal.publish(self.be, self.thermal())
            self.be.clock.sleep(dt)


def start_agent(agent, backend):
    """Start an agent and wait (simulated time) until its first pose arrived; returns the agent."""
    agent.start()
    deadline = backend.clock.now() + 2
    while agent.pose is None and backend.clock.now() < deadline:
        backend.clock.sleep(0.02)
    return agent


def stop_agent(agent, ual, backend, *scenes):
    """The teardown of start_agent: stop the scenes' threads, the backend's clock, the fake UAL, the agent."""
    for scene in scenes:
        scene.stop = True
    backend.shutdown = True
    ual.stop = True
    agent.shutdown()


def start_uav(backend, params=None, speedup=4.0):
    """A started UavAgent '2' (regions time out after 5 s unless params say otherwise) on a FakeUal, once
    its first pose arrived: the set-up every UAV task test needs. Returns (agent, ual)."""
    from mbzirc_agents.uav_agent import UavAgent
    ual = FakeUal(backend, speedup=speedup)
    return start_agent(UavAgent('2', backend, {'region_timeout': 5.0, **(params or {})}), backend), ual


def start_ugv(backend, pos, params=None, speedup=8.0):
    """A started UgvAgent '0' driving (the UAL's FLYING_AUTO) at pos on a FakeUal. Returns (agent, ual)."""
    from mbzirc_agents.ugv_agent import UgvAgent
    ual = FakeUal(backend, pos=pos, speedup=speedup)
    ual.state = State.FLYING_AUTO
    return start_agent(UgvAgent('0', backend, {'region_timeout': 5.0, **(params or {})}), backend), ual


def goal_pose(x, y, z, yaw=None, frame='arena'):
    """A task goal's PoseStamped; without a yaw its orientation is all zero (the tasks' "no heading")."""
    p = PoseStamped()
    p.header.frame_id = frame
    p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, z
    if yaw is not None:
        p.pose.orientation.z, p.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return p
