"""The mission's agents take ~smach_allow_init and ~smach_allow_debug from c3_sim.launch's smach_debug arg,
off by default (issue 19): a mission started without it accepts no container_init and offers no debugger
to whoever reaches its ROS master. Read from the launch files as roslaunch resolves them (no master)."""
import os

import pytest
import roslaunch.config
import rospkg

SMACH_PARAMS = ("smach_allow_init", "smach_allow_debug")
ROBOTS = 4  # three UAVs and the UGV, each with one agent


def _agent_smach_params(*launch_args):
    path = os.path.join(rospkg.RosPack().get_path("mbzirc_launchers"), "launch", "c3_sim.launch")
    config = roslaunch.config.load_config_default([(path, list(launch_args))], None, verbose=False)
    return {name: param.value for name, param in config.params.items()
            if name.rsplit("/", 1)[-1] in SMACH_PARAMS}


def test_mission_agents_refuse_init_and_debugging_by_default():
    params = _agent_smach_params()
    assert len(params) == ROBOTS * len(SMACH_PARAMS), sorted(params)
    assert all(name.split("/")[2] == "agent" for name in params), sorted(params)
    assert set(params.values()) == {False}, params


@pytest.mark.parametrize("value, expected", [("true", True), ("false", False)])
def test_smach_debug_arg_reaches_every_agent(value, expected):
    params = _agent_smach_params("smach_debug:=" + value)
    assert len(params) == ROBOTS * len(SMACH_PARAMS)
    assert set(params.values()) == {expected}, params
