"""Operator commands: what the page (or curl) may ask, checked before anything is called.

The page POSTs `{"command": <name>, "robot": "<id>" | "all"}` to /api/command; the node turns a valid
command into service calls of the central unit and the agents (see `SERVICES`), so that the same commands
work from the command line with `rosservice call`.
"""
from __future__ import annotations

from typing import NamedTuple, Optional

__all__ = ["Command", "parse_command", "COMMANDS", "SERVICES"]

# command -> (needs a robot, what the page's confirmation says)
COMMANDS = {
    "start_trial": (False, "Start the trial: the robots begin their work"),
    "pause": (False, "Pause the central unit: no new tasks are given"),
    "resume": (False, "Resume the central unit"),
    "send_home": (True, "Send the robot home"),
    "release": (True, "Release the robot: it takes the central unit's tasks again (after Home or a land)"),
    "land_all": (False, "EMERGENCY: every UAV lands where it is, the central unit pauses"),
}

# The services behind the commands (types: std_srvs/Trigger, std_srvs/SetBool).
SERVICES = {
    "start_trial": "/central_unit/start_trial",       # Trigger
    "pause": "/central_unit/pause",                   # SetBool (true = pause, false = resume)
    "send_home": "/mbzirc2020_%s/operator/go_home",   # Trigger, per robot
    "land": "/mbzirc2020_%s/operator/land",           # Trigger, per robot
    "release": "/mbzirc2020_%s/operator/release",     # Trigger, per robot
}


class Command(NamedTuple):
    name: str
    robot: str = ""       # robot id, "all", or "" for commands without a robot


def parse_command(req: dict, known_robots: list[str]) -> tuple[Optional[Command], str]:
    """(Command, '') for a valid request, else (None, reason)."""
    name = req.get("command")
    if not isinstance(name, str) or name not in COMMANDS:
        return None, "unknown command %r (known: %s)" % (name, ", ".join(sorted(COMMANDS)))
    needs_robot = COMMANDS[name][0]
    robot = req.get("robot", "")
    if not needs_robot:
        return Command(name), ""
    if isinstance(robot, int) and not isinstance(robot, bool):
        robot = str(robot)
    if not isinstance(robot, str) or not (robot == "all" or robot in known_robots):
        return None, "robot must be 'all' or one of %s, not %r" % (known_robots, robot)
    return Command(name, robot), ""
