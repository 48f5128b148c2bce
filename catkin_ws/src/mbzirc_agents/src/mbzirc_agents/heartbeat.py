"""Central-unit heartbeat watchdog (pure).

Why: if the central unit dies, an agent must not keep pumping or flying a stale plan. The agent feeds
`beat(now)` from `/central_unit/heartbeat` and calls `update(now)` at a fixed rate; the watchdog tells it
which safe reaction is due. Before the first heartbeat nothing is lost (an agent may run alone).
The agent passes wall-clock (monotonic) times, not ROS time: /clock comes from the ground station and
stops with the link, so a ROS-time watchdog would never fire.
"""
from __future__ import annotations

from typing import Optional

OK = 'ok'
LOST = 'lost'              # heartbeat missing longer than timeout: abort the task, hover
RETURN_HOME = 'return_home'  # missing longer than return_home_timeout too: go home and land


class HeartbeatWatchdog:
    """State of the link to the central unit.

    Args:
        timeout: s without a heartbeat before the link is LOST.
        return_home_timeout: s spent LOST before going home (counted from the loss).
    """

    def __init__(self, timeout: float = 5.0, return_home_timeout: float = 60.0) -> None:
        self.timeout = float(timeout)
        self.return_home_timeout = float(return_home_timeout)
        self.last_beat: Optional[float] = None

    def beat(self, now: float) -> None:
        """A heartbeat arrived at time now."""
        self.last_beat = now

    def reset(self) -> None:
        """Forget the link (e.g. when sim time jumps backwards)."""
        self.last_beat = None

    def state(self, now: float) -> str:
        """OK, LOST or RETURN_HOME at time now."""
        if self.last_beat is None:
            return OK
        silent = now - self.last_beat
        if silent < 0:           # time went backwards (rosbag loop, sim restart): trust the link
            self.last_beat = now
            return OK
        if silent <= self.timeout:
            return OK
        if silent <= self.timeout + self.return_home_timeout:
            return LOST
        return RETURN_HOME
