"""bench/replay_slam_bag.py on a small bag written here: a robot flies 10 s, its fix lost at 5 s, hector's map
frame 2 m and 0.3 rad off the arena's; the replay anchors it and scores the period without GNSS."""
import math
import os
import subprocess
import sys

import rosbag
import rospy
from geometry_msgs.msg import Pose, PoseArray, PoseStamped, Quaternion
from sensor_msgs.msg import NavSatStatus

SCRIPT = os.path.join(os.path.dirname(__file__), '..', 'bench', 'replay_slam_bag.py')
THETA, TX, TY = 0.3, 2.0, -1.0            # arena <- map


def _quat(yaw):
    return Quaternion(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def _write(path):
    c, s = math.cos(THETA), math.sin(THETA)
    with rosbag.Bag(path, 'w') as bag:
        for k in range(300):                                  # 30 Hz, 10 s, along y far from the buildings
            t = 1.0 + k / 30.0
            stamp = rospy.Time.from_sec(t)
            x, y, yaw = -10.0, -5.0 + 0.5 * (t - 1.0), 0.2
            if k % 15 == 0:
                truth = PoseArray()
                truth.header.stamp = stamp
                truth.poses = [Pose() for _ in range(3)]
                truth.poses[2].position.x, truth.poses[2].position.y = x, y
                bag.write('/sim/robots', truth, stamp)
            if k % 30 == 0:
                bag.write('/mbzirc2020_2/ual/gnss_status',
                          NavSatStatus(status=0 if t < 6.0 else -1), stamp)
            ual = PoseStamped()
            ual.header.stamp = stamp
            ual.pose.position.x, ual.pose.position.y, ual.pose.position.z = x, y, 3.0
            ual.pose.orientation = _quat(yaw)
            bag.write('/mbzirc2020_2/ual/pose', ual, stamp)
            if k % 2 == 0:
                mx, my = c * (x - TX) + s * (y - TY), -s * (x - TX) + c * (y - TY)
                slam = PoseStamped()
                slam.header.stamp, slam.header.frame_id = stamp, 'mbzirc2020_2/map'
                slam.pose.position.x, slam.pose.position.y = mx, my
                slam.pose.orientation = _quat(yaw - THETA)
                bag.write('/mbzirc2020_2/slam_out_pose', slam, stamp)


def test_the_replay_anchors_the_map_and_scores_the_period_without_gnss(tmp_path):
    bag = str(tmp_path / 'slam.bag')
    _write(bag)
    out = subprocess.run([sys.executable, SCRIPT, bag, '2', '--every', '0'], capture_output=True, text=True,
                         timeout=120, env=dict(os.environ))
    assert out.returncode == 0, out.stderr
    assert 'GNSS lost' in out.stdout and '1 period(s) without GNSS' in out.stdout, out.stdout
    line = next(l for l in out.stdout.splitlines() if 'truth samples' in l)
    rms = float(line.split('RMS')[1].split('m')[0])
    assert rms < 0.02, line


def test_a_bad_outline_param_is_a_clear_error(tmp_path):
    bag = str(tmp_path / 'slam.bag')
    _write(bag)
    out = subprocess.run([sys.executable, SCRIPT, bag, '2', '--outline', 'no_such=1'], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode != 0 and '--outline' in out.stderr
