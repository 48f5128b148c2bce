"""Shared main of the uav_agent and ugv_agent nodes: read ~params, build the agent, introspection, spin."""
from __future__ import annotations

from typing import Any, Dict

import rospy

from .robot_agent import DEFAULT_PARAMS
from .ros_backend import RosBackend


def read_params(extra: Dict[str, Any]) -> Dict[str, Any]:
    """Every ~param that is set (DEFAULT_PARAMS keys plus extra ones); unset ones keep their defaults."""
    params = {}
    for key in list(DEFAULT_PARAMS) + list(extra) + ['facade_holders']:
        if rospy.has_param('~' + key):
            params[key] = rospy.get_param('~' + key)
    return params


def main(agent_class: type, node_name: str, extra: Dict[str, Any]) -> None:
    """Run an agent node until Ctrl+C."""
    rospy.init_node(node_name)
    params = read_params(extra)
    agent_id = str(params.get('uav_id', rospy.get_param('~uav_id', '1')))
    ns = rospy.get_namespace().rstrip('/') or f'/mbzirc2020_{agent_id}'
    agent = agent_class(agent_id, RosBackend(), params, ns)
    agent.start()
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
