#!/usr/bin/env python3
"""Benchmark: what an agent pays for the raw thermal image between its extinguish_indoor_fire tasks.

Side by side in one run, on a roscore of its own: a publisher sends a robot's raw_temp_array (1024 float64,
as ual_sim's numpy_msg) at the camera's 14 Hz times the real-time factor (the benchmark missions run at 8x),
and two agent processes listen through the agents' own AgentInterface on a RosBackend, the task not running:
  subscribed  - add_subscriber (the whole trial; before): rospy deserialises every frame, the interface
                routes it to no one;
  on_demand   - add_demand (now): subscribed only while the task runs, so nothing between tasks.
Prints each process's CPU seconds per simulated second (CPU / the sim-seconds of frames sent, 14 a
sim-second) and the difference for the trial's 4 agents (3 UAVs + the UGV, one camera each).
Writes bench/results/raw_thermal.json.
Usage: bench_raw_thermal.py [--seconds 30] [--rtf 8]
"""
from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import tempfile
import time

from _common import SRC, load_averages, write_result
from _node_cpu import process_stat

TOPIC = '/mbzirc2020_1/teraranger_evo_thermal/raw_temp_array'
CAMERA_HZ = 14.0          # the TeraRanger Evo Thermal 33's frame rate (its datasheet)
AGENTS = 4


def cpu_seconds(pid: int) -> float:
    return process_stat(pid)[1]


def sent_count(path: str) -> tuple:
    """(time, frames sent) as the publisher last wrote them."""
    with open(path, encoding='utf-8') as f:
        t, n = f.read().split()
    return float(t), int(n)


def role_publisher(rate: float, count_file: str) -> None:
    import numpy as np
    import rospy
    from rospy.numpy_msg import numpy_msg
    from std_msgs.msg import Float64MultiArray
    rospy.init_node('thermal_publisher')
    pub = rospy.Publisher(TOPIC, numpy_msg(Float64MultiArray), queue_size=10)
    msg = Float64MultiArray(data=np.random.default_rng(1).normal(31.0, 0.5, 1024))
    r = rospy.Rate(rate)
    sent = 0
    while not rospy.is_shutdown():
        pub.publish(msg)
        sent += 1
        if sent % 50 == 0:
            with open(count_file, 'w', encoding='utf-8') as f:
                f.write(f'{time.monotonic()} {sent}')
        r.sleep()


def role_agent(how: str) -> None:
    sys.path[:0] = [os.path.join(SRC, 'mbzirc_agents', 'src')]
    import rospy
    from rospy.numpy_msg import numpy_msg
    from std_msgs.msg import Float64MultiArray
    from mbzirc_agents.agent_interface import AgentInterface
    from mbzirc_agents.ros_backend import RosBackend
    rospy.init_node(f'agent_{how}')
    iface = AgentInterface(RosBackend())
    if how == 'subscribed':
        iface.add_subscriber('extinguish_indoor_fire', TOPIC, numpy_msg(Float64MultiArray), lambda m: None)
    else:
        iface.add_demand('extinguish_indoor_fire', TOPIC, numpy_msg(Float64MultiArray), lambda m: None)
    rospy.spin()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--seconds', type=float, default=30.0)
    ap.add_argument('--rtf', type=float, default=8.0)
    ap.add_argument('--role', default=None)
    ap.add_argument('--count-file', default=None)
    args = ap.parse_args()
    if args.role == 'publisher':
        role_publisher(CAMERA_HZ * args.rtf, args.count_file)
        return 0
    if args.role:
        role_agent(args.role)
        return 0
    s = socket.socket()
    s.bind(('localhost', 0))
    port = s.getsockname()[1]
    s.close()
    env = dict(os.environ, ROS_MASTER_URI=f'http://localhost:{port}', ROS_HOSTNAME='localhost')
    procs = [subprocess.Popen(['roscore', '-p', str(port)], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)]
    try:
        time.sleep(5.0)
        count_file = os.path.join(tempfile.mkdtemp(), 'sent')
        me = [sys.executable, os.path.abspath(__file__), '--rtf', str(args.rtf), '--count-file', count_file,
              '--role']
        agents = {how: subprocess.Popen(me + [how], env=env) for how in ('subscribed', 'on_demand')}
        procs += list(agents.values())
        procs.append(subprocess.Popen(me + ['publisher'], env=env))
        time.sleep(10.0)                                  # connected, imports done
        start = {how: cpu_seconds(p.pid) for how, p in agents.items()}
        sent0 = sent_count(count_file)
        time.sleep(args.seconds)
        used = {how: cpu_seconds(p.pid) - start[how] for how, p in agents.items()}
        sent1 = sent_count(count_file)
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
    rate = (sent1[1] - sent0[1]) / max(1e-9, sent1[0] - sent0[0])
    sim = args.seconds * rate / CAMERA_HZ          # the sim-seconds of frames sent (the publisher may lag)
    per_sim = {how: round(c / sim, 5) for how, c in used.items()}
    result = {'rtf': args.rtf, 'camera_hz': CAMERA_HZ, 'wall_s': args.seconds, 'frames_per_wall_s': round(rate, 1),
              'cpu_s_per_sim_s_per_agent': per_sim,
              'saved_cpu_s_per_sim_s_4_agents': round(AGENTS * (per_sim['subscribed'] - per_sim['on_demand']), 4),
              'load_average': load_averages()}
    print(f"{rate:.0f} frames/s wall ({CAMERA_HZ * args.rtf:.0f} asked); per agent, CPU-s per sim-s between "
          f"tasks: subscribed {per_sim['subscribed']:.4f}, on demand {per_sim['on_demand']:.4f}; the trial's "
          f"{AGENTS} agents save "
          f"{result['saved_cpu_s_per_sim_s_4_agents']:.4f} (load {result['load_average']})")
    write_result('raw_thermal', result)
    return 0


if __name__ == '__main__':
    sys.exit(main())
