"""smach: task-level state machines (API-compatible with executive_smach 2.5, written from scratch).

Pure Python, no ROS import; ``smach_ros`` plugs ROS logging and shutdown in.
"""
from smach.log import (set_loggers, loginfo, logwarn, logdebug, logerr, set_shutdown_check,  # noqa: F401
                       is_shutdown)
from smach.exceptions import (InvalidStateError, InvalidTransitionError, InvalidConstructionError,  # noqa: F401
                              InvalidUserCodeError, UndeclaredKeyError)
from smach.util import has_smach_interface  # noqa: F401
from smach.state import State, CBState, CBInterface, cb_interface  # noqa: F401
from smach.user_data import UserData, Remapper, Const, get_const  # noqa: F401
from smach.container import Container  # noqa: F401
from smach.state_machine import StateMachine  # noqa: F401
from smach.sequence import Sequence  # noqa: F401
from smach.concurrence import Concurrence  # noqa: F401
from smach.iterator import Iterator  # noqa: F401

__all__ = ["State", "CBState", "cb_interface", "CBInterface", "UserData", "Remapper", "Const", "get_const",
           "Container", "StateMachine", "Sequence", "Concurrence", "Iterator", "InvalidStateError",
           "InvalidTransitionError", "InvalidConstructionError", "InvalidUserCodeError", "UndeclaredKeyError",
           "set_loggers", "loginfo", "logwarn", "logerr", "logdebug", "is_shutdown", "set_shutdown_check",
           "has_smach_interface"]
