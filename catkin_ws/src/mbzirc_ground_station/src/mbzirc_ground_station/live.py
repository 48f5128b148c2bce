"""The live frame source: the state fed by ROS callbacks, and the operator commands' log (no ROS import).

ROS callbacks and the web server's threads share one lock. `clock()` is the node's ROS time (sim time in
the mission) and `wall()` the wall clock: a graph that went silent (the mission ended or the master is
gone) shows as "no messages for N s" even though sim time stopped with it.
"""
from __future__ import annotations

import threading
import time
from typing import Any, Callable, Optional

from .commands import COMMANDS, Command, parse_command
from .state import GroundStationState, robot_name

__all__ = ["LiveSource"]

SILENT_WALL_S = 3.0


class LiveSource:
    """Thread-safe wrapper of a GroundStationState for a running ROS graph.

    Args:
        state: the state to feed.
        clock: sim time now (seconds).
        run_command: executes a valid Command, returns (ok, message); None = commands disabled.
        wall: wall clock (seconds), for the silence check.
    """

    def __init__(self, state: GroundStationState, clock: Callable[[], float],
                 run_command: Optional[Callable[[Command], tuple[bool, str]]] = None,
                 wall: Callable[[], float] = time.monotonic) -> None:
        self.state = state
        self.clock = clock
        self.run_command = run_command
        self.wall = wall
        self.lock = threading.Lock()
        self.last_wall: Optional[float] = None
        self._command_lock = threading.Lock()

    def apply(self, topic: str, msg: Any) -> None:
        now = self.clock()
        with self.lock:
            self.state.apply(topic, msg, now)
            self.last_wall = self.wall()

    def frame(self, tracks: bool = False) -> dict:
        with self.lock:
            out = self.state.frame(max(self.clock(), self.state.now), tracks=tracks)
            silent = None if self.last_wall is None else round(self.wall() - self.last_wall, 1)
        out["live"] = {"silent_s": silent, "silent": silent is None or silent > SILENT_WALL_S}
        return out

    def log(self, source: str, text: str) -> None:
        with self.lock:
            self.state.add_log(max(self.clock(), self.state.now), source, text)

    def command(self, req: dict) -> tuple[int, dict]:
        """The /api/command handler: check, run, log; (HTTP code, reply)."""
        if self.run_command is None:
            return 409, {"error": "commands are disabled"}
        with self.lock:
            known = sorted(self.state.robots)
        cmd, why = parse_command(req, known)
        if cmd is None:
            self.log("operator", "refused: %s" % why)
            return 400, {"error": why}
        who = "" if not cmd.robot else (" all robots" if cmd.robot == "all" else " " + robot_name(cmd.robot))
        self.log("operator", "%s%s: sent" % (cmd.name, who))
        with self._command_lock:   # one command at a time: an emergency land is not interleaved with others
            ok, message = self.run_command(cmd)
        self.log("operator", "%s%s: %s%s" % (cmd.name, who, "done" if ok else "FAILED",
                                              (" - " + message) if message else ""))
        return (200 if ok else 502), {"ok": ok, "message": message, "command": cmd.name, "robot": cmd.robot,
                                      "confirm": COMMANDS[cmd.name][1]}
