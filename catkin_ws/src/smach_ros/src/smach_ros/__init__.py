"""smach_ros: ROS states and tools for smach (API-compatible with executive_smach 2.5, from scratch).

Importing it routes smach's logging to rospy and makes containers stop on rospy shutdown.
"""
from smach_ros.log_routing import route_smach_to_rospy

route_smach_to_rospy()

from smach_ros.simple_action_state import SimpleActionState  # noqa: E402,F401
from smach_ros.service_state import ServiceState  # noqa: E402,F401
from smach_ros.monitor_state import MonitorState, ConditionState  # noqa: E402,F401
from smach_ros.action_server_wrapper import ActionServerWrapper  # noqa: E402,F401
from smach_ros.introspection import IntrospectionServer, IntrospectionClient  # noqa: E402,F401
from smach_ros.util import set_preempt_handler  # noqa: E402,F401
from smach_ros.debugger import breakpoint_here  # noqa: E402,F401

__all__ = ["SimpleActionState", "ServiceState", "MonitorState", "ConditionState", "ActionServerWrapper",
           "IntrospectionServer", "IntrospectionClient", "set_preempt_handler", "breakpoint_here"]
