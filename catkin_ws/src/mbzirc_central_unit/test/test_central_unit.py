#!/usr/bin/env python3
"""Integration test of the central unit node against fake agents: heartbeat, a complete mission,
reassignment of a silent agent's floor and work for it on return, a restart of the node mid-mission, and
a crashed UAV whose reserved regions are freed."""
import json
import os
import sys
import unittest

import rosnode
import rospy
import rostest
from std_msgs.msg import Header, String

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fake_agents import FakeAgents  # noqa: E402


class TestCentralUnit(unittest.TestCase):
    def test_mission_with_silent_agent_and_restart(self):
        agents = FakeAgents(task_time=0.2)
        beats, status = [], {}

        def on_status(m):
            status.update(json.loads(m.data))
        rospy.Subscriber("/central_unit/heartbeat", Header, lambda m: beats.append(rospy.get_time()))
        rospy.Subscriber("/central_unit/status", String, on_status)
        deadline = rospy.get_time() + 90.0

        def wait_for(cond, timeout):
            end = rospy.get_time() + timeout
            while not rospy.is_shutdown() and rospy.get_time() < end:
                if cond():
                    return True
                rospy.sleep(0.1)
            return False

        # Heartbeat at ~2 Hz.
        self.assertTrue(wait_for(lambda: len(beats) >= 5, 10.0), "no heartbeat")
        t0, n0 = rospy.get_time(), len(beats)
        rospy.sleep(3.0)
        rate = (len(beats) - n0) / (rospy.get_time() - t0)
        self.assertGreater(rate, 1.5)
        self.assertLess(rate, 2.6)

        # Agent 2 takes a floor; then it goes silent: the floor is released and nobody sends it goals.
        self.assertTrue(wait_for(lambda: "2" in status.get("floor_owner", {}).values(), 20.0),
                        f"agent 2 never owned a floor: {status}")
        agents.silent.add("2")
        self.assertTrue(wait_for(lambda: "2" not in status.get("floor_owner", {}).values()
                                 and not status["agents"]["2"]["alive"], 10.0), f"floor not released: {status}")
        t_silent = rospy.get_time()
        rospy.sleep(2.0)
        self.assertFalse([r for r in agents.received if r[1] == "2" and r[0] > t_silent + 0.5],
                         "goals were sent to a silent agent")
        agents.silent.discard("2")
        t_back = rospy.get_time()
        self.assertTrue(wait_for(lambda: any(r[1] == "2" and r[0] > t_back for r in agents.received), 10.0),
                        "agent 2 got no work after it came back")

        # Restart the central unit (respawn in the launch file); the mission goes on.
        t_kill = rospy.get_time()
        rosnode.kill_nodes(["/central_unit"])
        rospy.sleep(1.0)
        self.assertTrue(wait_for(lambda: agents.mission.all_out(), deadline - rospy.get_time()),
                        f"not every fire out: {agents.mission.fires} / {status}")
        # the respawned central unit ticks with UAV 3 alive (it may have missed UAV 3 flying: the restart
        # can come as it goes home; a crash is judged on what the running central unit saw)
        self.assertTrue(wait_for(lambda: status.get("t", 0.0) > t_kill + 1.0 and status["agents"]["3"]["alive"], 30.0),
                        f"the central unit did not come back: {status}")
        self.assertTrue(any(r[1] == "0" and r[2] == "search_indoor" for r in agents.received))

        # UAV 3 (it flew) falls back to UNINITIALIZED, the simulator's crash state: its regions are freed
        # and it gets no more goals. Within 10 s: at once if the central unit saw it fly, else after
        # bookkeeping.CRASH_CONFIRM_S (3 s) of UNINITIALIZED, plus a few ticks.
        self.assertEqual(agents.freed, [])
        with agents.lock:
            agents.mission.agents["3"].ual_state = 0
        self.assertTrue(wait_for(lambda: "3" in agents.freed, 10.0), "the crashed UAV's regions were not freed")
        t_crash = rospy.get_time()
        rospy.sleep(2.0)
        self.assertFalse([r for r in agents.received if r[1] == "3" and r[0] > t_crash])


if __name__ == "__main__":
    rospy.init_node("test_central_unit")
    rostest.rosrun("mbzirc_central_unit", "test_central_unit", TestCentralUnit)
