"""How long the central unit waits for each task's result before it gives the goal up (pure).

Why: a goal used to wait for its result forever. An agent whose state machine died (a zombie that still
says "idle" on its data_feed), a result lost on a faded link or an agent stuck in a call kept the robot's
floor taken for the rest of the mission. Now a goal older than its task's bound (sim seconds, about three
times the longest run seen in the 20-seed benchmark and the fault suite, so a slow but working robot is
never cut short) is cancelled and counted as a failure of that task; the strategy then reassigns the work.

The bound of each task and why is in the package README ("Goal timeouts").
Unknown tasks get DEFAULT_TIMEOUT_S. `~task_timeout_scale` (1.0) scales them all.
"""
from __future__ import annotations

from typing import Any, Dict, List, Tuple

from . import constants as C

TASK_TIMEOUT_S: Dict[str, float] = {
    C.TAKE_OFF: 90.0, C.LAND: 120.0, C.GO_TO: 240.0, C.FOLLOW_PATH: 360.0, C.HOVER: 60.0,
    C.SEARCH_FACADE: 600.0, C.GO_TO_FACADE_FIRE: 240.0, C.EXTINGUISH_FACADE_FIRE: 420.0,
    C.LOOK_FOR_GROUND_FIRES: 600.0, C.EXTINGUISH_GROUND_FIRE: 300.0, C.ENTER_BUILDING: 420.0,
    C.SEARCH_INDOOR: 900.0, C.EXTINGUISH_INDOOR_FIRE: 420.0, C.GO_HOME_AND_REFILL: 600.0,
}
DEFAULT_TIMEOUT_S = 600.0


def timeout_of(task: str, goal: Dict[str, Any], scale: float = 1.0) -> float:
    """Seconds (sim) the central unit waits for the result of a goal of `task`."""
    base = TASK_TIMEOUT_S.get(task, DEFAULT_TIMEOUT_S)
    if task == C.HOVER:
        try:
            base += max(float(goal.get("duration", 0.0)), 0.0)
        except (TypeError, ValueError):
            pass
    return base * scale


class GoalClock:
    """When each agent's goal in flight was sent; which ones are overdue."""

    def __init__(self, scale: float = 1.0) -> None:
        self.scale = float(scale)
        self.sent: Dict[str, Tuple[Any, float]] = {}      # agent id -> (command, sim time sent)

    def started(self, cmd: Any, now: float) -> None:
        self.sent[cmd.agent_id] = (cmd, now)

    def overdue(self, in_flight: Dict[str, Any], now: float) -> List[Tuple[Any, float]]:
        """(command, seconds waited) of the goals in flight older than their bound; forgets goals no longer
        in flight. Time going back (a restarted simulation) restarts the count."""
        out = []
        for agent_id, (cmd, t0) in list(self.sent.items()):
            if in_flight.get(agent_id) is not cmd:
                del self.sent[agent_id]
                continue
            if now < t0:
                self.sent[agent_id] = (cmd, now)
                continue
            if now - t0 > timeout_of(cmd.task, cmd.goal, self.scale):
                out.append((cmd, now - t0))
                del self.sent[agent_id]
        return out
