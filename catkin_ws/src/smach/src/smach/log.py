"""Logging hooks and the shutdown check of smach.

smach itself has no ROS dependency, so every message goes through four replaceable functions;
``smach_ros`` routes them to rospy on import, and ``set_shutdown_check`` lets it make every
container loop stop when the node shuts down.
"""
from __future__ import annotations

import sys
from typing import Callable

__all__ = ["set_loggers", "loginfo", "logwarn", "logdebug", "logerr", "set_shutdown_check", "is_shutdown"]

LogFn = Callable[[str], None]


def _print_info(msg: str) -> None:
    print("[  INFO ] : " + str(msg))


def _print_warn(msg: str) -> None:
    print("[  WARN ] : " + str(msg), file=sys.stderr)


def _print_debug(msg: str) -> None:
    """Debug output is silent by default (upstream prints it; it drowns the useful lines)."""


def _print_err(msg: str) -> None:
    print("[ ERROR ] : " + str(msg), file=sys.stderr)


_loggers: dict[str, LogFn] = {"info": _print_info, "warn": _print_warn, "debug": _print_debug,
                              "error": _print_err}
_shutdown_check: Callable[[], bool] = lambda: False


def set_loggers(info: LogFn, warn: LogFn, debug: LogFn, error: LogFn) -> None:
    """Replace the four logging functions (argument order as upstream: info, warn, debug, error)."""
    _loggers.update(info=info, warn=warn, debug=debug, error=error)


def loginfo(msg: str) -> None:
    _loggers["info"](msg)


def logwarn(msg: str) -> None:
    _loggers["warn"](msg)


def logdebug(msg: str) -> None:
    _loggers["debug"](msg)


def logerr(msg: str) -> None:
    _loggers["error"](msg)


def set_shutdown_check(cb: Callable[[], bool]) -> None:
    """Install the function container loops poll to know they must stop (rospy.is_shutdown in ROS)."""
    global _shutdown_check
    _shutdown_check = cb


def is_shutdown() -> bool:
    return bool(_shutdown_check())
