"""Shared main of the uav_agent and ugv_agent nodes: read ~params, build the agent, introspection, spin."""
from __future__ import annotations

import os

# One OpenBLAS thread unless the user set another number (fire_detector README, "single-threaded numerics"):
# set here, the first module the agent scripts import, before NumPy loads.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from typing import Any, Dict  # noqa: E402

import rospy  # noqa: E402

from .operator_services import OperatorServices  # noqa: E402
from .params import OTHER_NODE_PARAMS, AgentParams, check_values
from .ros_backend import RosBackend


def read_params() -> Dict[str, Any]:
    """The agent ~params that are set and well-formed (unset ones keep their defaults); each unknown or
    malformed one is logged as an error and left out: the node runs on with the default."""
    private = rospy.get_param('~', {})
    values = {k: v for k, v in private.items() if k not in OTHER_NODE_PARAMS}
    good, problems = check_values(values)
    for problem in problems:
        rospy.logerr(f'{problem}: ignored')
    return good


def main(agent_class: type, node_name: str) -> None:
    """Run an agent node until Ctrl+C."""
    rospy.init_node(node_name)
    params = read_params()
    agent_id = str(params.get('uav_id', AgentParams().uav_id))
    ns = rospy.get_namespace().rstrip('/') or f'/mbzirc2020_{agent_id}'
    agent = agent_class(agent_id, RosBackend(), params, ns)
    agent.set_mission(str(rospy.get_param('/run_id', '') or ''))
    agent.start()
    operator = OperatorServices(agent, ns)   # noqa: F841 - the ground station's commands (operator_services.py)
    sis = None
    try:
        import smach_ros
        sis = smach_ros.IntrospectionServer(ns, agent.sm, '/SM_ROOT')
        sis.start()
    except Exception as e:  # the agent still works without the viewer
        rospy.logerr(f'no SMACH introspection: {e!r}')
    rospy.on_shutdown(agent.shutdown)
    rospy.loginfo(f'{node_name} {agent_id} ready: tasks {sorted(agent.specs)}')
    rospy.spin()
    if sis is not None:
        sis.stop()
