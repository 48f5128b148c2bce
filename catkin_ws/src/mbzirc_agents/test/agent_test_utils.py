"""Helpers of the agents' rostests: action clients, poses, waiting on sim time with a wall-time cap."""
import math
import time

import actionlib
import rospy
from geometry_msgs.msg import PoseArray, PoseStamped
from mbzirc_comm_objs import msg as M


def pose(x, y, z, yaw=None):
    p = PoseStamped()
    p.header.frame_id = 'arena'
    p.pose.position.x, p.pose.position.y, p.pose.position.z = x, y, z
    if yaw is not None:
        p.pose.orientation.z, p.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return p


def client(robot, task, action, wait=60.0):
    """A connected SimpleActionClient of /mbzirc2020_<robot>/<task>_action."""
    c = actionlib.SimpleActionClient(f'/mbzirc2020_{robot}/{task}_action', getattr(M, f'{action}Action'))
    if not c.wait_for_server(rospy.Duration(wait)):
        raise AssertionError(f'no server {task} of robot {robot}')
    return c


def run(robot, task, action, wall_timeout=120.0, feedback=None, **fields):
    """Send a goal and wait for it (wall-time cap); returns (GoalStatus, result)."""
    c = client(robot, task, action)
    goal = getattr(M, f'{action}Goal')(**fields)
    # actionlib's wait_for_server() can return before the server's goal subscriber has connected to our
    # publisher, and a goal sent in that gap is silently lost (a known race, seen on a loaded machine).
    # A goal that nobody acknowledged (no status, feedback or result at all) within 10 s is therefore sent
    # again, at most twice. (5 s was too short on a loaded machine: a 5-s blanket drop's result arrived just
    # after it, the goal was sent again and failed 'no blanket attached'.)
    heard = []

    def on_feedback(f):
        heard.append(f)
        if feedback is not None:
            feedback(f)

    for _ in range(3):
        c.send_goal(goal, feedback_cb=on_feedback)
        if wait_wall(lambda: heard or c.simple_state != actionlib.SimpleGoalState.PENDING, 10.0):
            break
    if not wait_wall(lambda: done(c), wall_timeout):
        c.cancel_goal()
        raise AssertionError(f'{task} of {robot} did not finish in {wall_timeout} s')
    return c.get_state(), c.get_result()


def done(c):
    """True once the goal's result arrived (its status may come first: then get_result() is still None)."""
    return c.simple_state == actionlib.SimpleGoalState.DONE


def wait_wall(cond, timeout, step=0.1):
    """Poll cond in wall time (sim time may run faster)."""
    end = time.time() + timeout
    while time.time() < end:
        if cond():
            return True
        time.sleep(step)
    return cond()


class SimRobots:
    """Ground truth poses from /sim/robots (tests only; agents never read /sim)."""

    def __init__(self):
        self.ids = [int(i) for i in rospy.get_param('/sim/robot_ids', [])]
        self.poses = {}
        self.min_distance = float('inf')
        rospy.Subscriber('/sim/robots', PoseArray, self.on_msg)

    def on_msg(self, msg):
        self.ids = [int(i) for i in rospy.get_param('/sim/robot_ids', self.ids)] if not self.ids else self.ids
        pts = {}
        for i, p in zip(self.ids, msg.poses):
            pts[i] = (p.position.x, p.position.y, p.position.z)
        self.poses = pts
        vals = list(pts.values())
        for a in range(len(vals)):
            for b in range(a + 1, len(vals)):
                self.min_distance = min(self.min_distance, math.dist(vals[a], vals[b]))


class SimFires:
    """Ground truth of the fires and crashes from /sim/fires and /sim/score (tests only; agents never read
    /sim). `fires` is the latest FireStateArray, `crashed` the crashed robots' ids."""

    def __init__(self, wait=60.0):
        from ual_sim.msg import FireStateArray, Score
        self.fires = None
        self.crashed = []
        rospy.Subscriber('/sim/fires', FireStateArray, lambda m: setattr(self, 'fires', m))
        rospy.Subscriber('/sim/score', Score, lambda m: setattr(self, 'crashed', list(m.crashed_robots)))
        assert wait_wall(lambda: self.fires is not None, wait), 'no /sim/fires'

    def fire(self, fid):
        """The FireState of holder fid."""
        return [f for f in self.fires.fires if f.id == fid][0]
