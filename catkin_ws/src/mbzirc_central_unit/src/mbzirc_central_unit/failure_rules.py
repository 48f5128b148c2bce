"""Two failure kinds the strategy treats apart from a plain failure (pure, sim time).

1. A blocked leg. The agents' leg guard holds an indoor straight leg that the robot's laser sees blocked and
   fails the task with 'a laser return <d> m ahead blocks the leg to (x, y) ...: holding'. Sent again at
   once, the same task fails again within 0.1-2 s, over and over (realistic seed 106). Rule: the same
   command (agent, task, target) is not sent again before a back-off that doubles with each blocked failure
   (`leg_blocked_backoff` s, at most `leg_blocked_backoff_max` s); after `max_blocked_legs` blocked
   failures of it the agent gives that target up (another robot may take it, or nobody: logged).
2. A fire not seen hot. extinguish_facade_fire / extinguish_indoor_fire abort with 'fire N not seen hot
   from the watering pose: not judged out: ...' after pumping water on the fire's locked hole (facade) or
   its confirmed track (indoors) without one hot answer there (the agents' cold_check.NOT_SEEN_HOT; every
   such abort pumps first). A fire already put out reads like that, and the estimator keeps it active.
   Rule: after `not_seen_hot_limit` such aborts (any robots) the fire is "probably out, unconfirmed": no
   robot is sent to it while other work remains; it may be revisited when nothing else is left. Other
   failures (fire not found, no water flows, time-outs) never count: a fire merely not found is not out.

The action results have no structured field for either kind (mbzirc_comm_objs, pinned): the abort text
is matched on the agents' fixed phrases below.
"""
from __future__ import annotations

from collections import Counter
from typing import Any, Optional

from . import constants as C

# the agents' fixed phrases (leg_guard.py, tasks/cold_check.py NOT_SEEN_HOT)
LEG_BLOCKED_TEXT = "blocks the leg"
NOT_SEEN_HOT_TEXT = "not seen hot from the watering pose"

LEG_BLOCKED = "leg blocked"
NOT_SEEN_HOT = "not seen hot"


def failure_kind(task: str, message: str) -> Optional[str]:
    """LEG_BLOCKED, NOT_SEEN_HOT (only from the extinguish tasks) or None for any other failure."""
    if LEG_BLOCKED_TEXT in message:
        return LEG_BLOCKED
    if task in (C.EXTINGUISH_FACADE_FIRE, C.EXTINGUISH_INDOOR_FIRE) and NOT_SEEN_HOT_TEXT in message:
        return NOT_SEEN_HOT
    return None


class LegBackoff:
    """Blocked-leg failures per (agent, task, target) and when that command may be sent again."""

    def __init__(self, backoff: float, backoff_max: float, max_blocked: int) -> None:
        self.backoff = backoff
        self.backoff_max = backoff_max
        self.max_blocked = max_blocked
        self.blocked: Counter[tuple[str, str, Any]] = Counter()
        self.until: dict[tuple[str, str, Any], float] = {}

    def note(self, key: tuple[str, str, Any], now: float) -> tuple[bool, str]:
        """A blocked-leg failure of `key` at sim time `now`: (given up, log line)."""
        self.blocked[key] += 1
        n = self.blocked[key]
        agent, task, target = key
        if n >= self.max_blocked:
            self.until.pop(key, None)
            return True, (f"{agent} {task} {target}: leg blocked {n} times (limit {self.max_blocked}): "
                          "given up by this robot, left to another robot if one may take it")
        delay = min(self.backoff * 2 ** (n - 1), self.backoff_max)
        self.until[key] = now + delay
        return False, (f"{agent} {task} {target}: leg blocked ({n} of {self.max_blocked}): "
                       f"not sent again before {delay:.0f} s (t = {now + delay:.1f})")

    def waiting(self, key: tuple[str, str, Any], now: float) -> bool:
        """True while `key` is backing off; time going back (a restarted simulation) ends the wait."""
        t = self.until.get(key)
        if t is None or now >= t or now < t - self.backoff_max:
            self.until.pop(key, None)
            return False
        return True


class UnconfirmedFires:
    """Fires that repeatedly were not seen hot after water from their watering pose: probably out."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.aborts: Counter[int] = Counter()

    def note(self, fire_id: int, agent_id: str) -> Optional[str]:
        """A not-seen-hot abort on `fire_id`; the log line when the fire just became probably out."""
        self.aborts[fire_id] += 1
        if self.aborts[fire_id] == self.limit:
            return (f"fire {fire_id}: not seen hot after water from its watering pose {self.limit} times (last by "
                    f"{agent_id}): probably out, unconfirmed; no robot is sent to it while other work remains")
        return None

    def probably_out(self, fire_id: int) -> bool:
        return self.aborts[fire_id] >= self.limit
