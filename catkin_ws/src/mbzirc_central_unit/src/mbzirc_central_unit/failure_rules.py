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
   such abort pumps first). Two causes read alike: a fire already put out, and an estimate off the fire
   (realistic seed 108, fire D_3: the estimate 1.2 m off, the UAV locked on a hole 2.3 m from the fire,
   'not seen hot' twice, no water ever went into it). What tells them apart: whether some extinguish task
   on the fire SUCCEEDED, which the agents' tasks do only after seeing it hot from their watering pose and
   watering it (out, or the tank ran dry before the cold answers: cold_check.dry_tank_verdict). An abort
   that spent no water never counts: indoors 'hot before aiming at its hot spot, cold after; no water spent'
   says the fire was seen hot a moment before (realistic seed 108: in2_w, 86 % full, judged probably out by
   one such abort, left burning).
   Rule: after `not_seen_hot_limit` such aborts (any robots) the fire is doubted: no robot is sent to it
   while other work remains; it may be revisited when nothing else is left. Watered hot before: "probably
   out, unconfirmed" (its floor is done, water_decider.facade_floors_open). Never watered hot: "misplaced":
   its facade floor is searched again (once). A search that reports a doubted fire (the searches report only
   fires they saw hot: a facade search at a holder, an indoor search from a room; the estimator moved the
   track onto the new sightings: a detection within its gates updates it, no new track) makes it a target
   again, once per fire; doubted again, it stays so until the end.
   A facade fire watered hot before is doubted after `facade_top_up_limit` (1) such aborts: its hole was
   locked by the circle detector and watered ~top_up_time s, and a facade fire the thermal camera no longer
   sees hot is at 85 % or more (the detector's contrast test), which that water finishes; the second abort
   only poured more on a fire already out (realistic seed 102 on de9a852: C_3 and A_4, out at 157 and 107 s,
   each got two top-up pours at 257-322 s, and A_0 a fourth one). Indoors the top-up aims on the track, not
   on a hole, and may miss (closed loop top-ups at 97 %: 6 of 12 short): the general limit stays.
   Other failures (fire not found, no water
   flows, time-outs) never count: a fire merely not found is not out.
3. A window not sensed. enter_building fails with '<window|door> not found ahead by the laser in <s> s (no
   window <w> m wide seen): holding' when the laser, from in front of it, sees no opening as wide as the
   frame needs there: a fact of the window (an interior wall's end behind it, which an explored layout
   does not know), not of the try; one more try covers a failure of the robot's own (its approach off, a
   gust). Rule: after `UNSEEN_WINDOW_TRIES` such failures an agent gives that window up (as after
   `max_failures` others; bookkeeping.window_ok then leaves one try to another agent). Explore + GNSS-denied
   seeds 109 and 112: each UAV sent to facade B's split floor-1 window spent three tries of ~23 s on it.

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
NO_WATER_TEXT = "no water spent"   # tasks/indoor.py: an abort before any water

WINDOW_UNSEEN_TEXT = ("not found ahead by the laser", "wide seen)")   # tasks/passage.py, both in the text

LEG_BLOCKED = "leg blocked"
NOT_SEEN_HOT = "not seen hot"
WINDOW_UNSEEN = "window not sensed"
UNSEEN_WINDOW_TRIES = 2      # tries of an agent at a window its laser saw no opening in (rule 3)


def failure_kind(task: str, message: str) -> Optional[str]:
    """LEG_BLOCKED, NOT_SEEN_HOT (only from the extinguish tasks), WINDOW_UNSEEN (only from enter_building)
    or None for any other failure."""
    if LEG_BLOCKED_TEXT in message:
        return LEG_BLOCKED
    if task == C.ENTER_BUILDING and all(text in message for text in WINDOW_UNSEEN_TEXT):
        return WINDOW_UNSEEN
    if task in (C.EXTINGUISH_FACADE_FIRE, C.EXTINGUISH_INDOOR_FIRE) and NOT_SEEN_HOT_TEXT in message \
            and NO_WATER_TEXT not in message:
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
    """Fires repeatedly not seen hot after water from their watering pose: probably out when some extinguish
    task on them succeeded (watered hot), else misplaced (see the module docstring, 2.)."""

    def __init__(self, limit: int, facade_top_up_limit: int = C.FACADE_TOP_UP_LIMIT) -> None:
        self.limit, self.facade_top_up_limit = limit, facade_top_up_limit
        self.aborts: Counter[int] = Counter()
        self.watered_hot: set[int] = set()
        self.facade: set[int] = set()             # fires whose aborts came from extinguish_facade_fire
        self.found_again_once: set[int] = set()

    def limit_of(self, fire_id: int) -> int:
        """The aborts after which `fire_id` is doubted (module docstring, 2.)."""
        if fire_id in self.facade and fire_id in self.watered_hot:
            return min(self.limit, self.facade_top_up_limit)
        return self.limit

    def note_watered_hot(self, fire_id: int) -> None:
        """An extinguish task on `fire_id` succeeded: it saw the fire hot from its watering pose and watered it."""
        self.watered_hot.add(fire_id)

    def note(self, fire_id: int, agent_id: str, facade: bool = False) -> Optional[str]:
        """A not-seen-hot abort on `fire_id` (facade: of extinguish_facade_fire); the log line when the fire just
        became doubted."""
        if facade:
            self.facade.add(fire_id)
        self.aborts[fire_id] += 1
        limit = self.limit_of(fire_id)
        if self.aborts[fire_id] != limit:
            return None
        head = (f"fire {fire_id}: not seen hot after water from its watering pose {limit} time"
                f"{'s' if limit > 1 else ''} (last by {agent_id})")
        if fire_id in self.watered_hot:
            return (f"{head}, watered hot before: probably out, unconfirmed; no robot is sent to it while other "
                    "work remains")
        again = ("its floor is searched again" if fire_id not in self.found_again_once
                 else "found again once already: left until nothing else remains")
        return (f"{head}, never watered hot: misplaced (its estimate off the fire), not a target while other work "
                f"remains; {again}")

    def note_found(self, fire_id: int, search: str = "search_facade") -> Optional[str]:
        """A search (its task name) reported `fire_id`, seen hot (a facade search at a holder, its track near;
        an indoor search from a room): a doubted fire is a target again (its count starts again), once per
        fire; the log line then. An indoor fire seen from outside through a window was doubted after water
        from outside and found hot by every indoor search after (explore + GNSS-denied seed 104)."""
        if not self.doubted(fire_id) or fire_id in self.found_again_once:
            return None
        what = "probably out" if self.probably_out(fire_id) else "misplaced"
        self.found_again_once.add(fire_id)
        del self.aborts[fire_id]
        return f"fire {fire_id}: {what}, found again (hot) by {search}: a target again at its estimate"

    def doubted(self, fire_id: int) -> bool:
        """Probably out or misplaced: no robot is sent to it while other work remains."""
        return self.aborts[fire_id] >= self.limit_of(fire_id)

    def probably_out(self, fire_id: int) -> bool:
        return self.doubted(fire_id) and fire_id in self.watered_hot

    def misplaced(self, fire_id: int) -> bool:
        return self.doubted(fire_id) and fire_id not in self.watered_hot

    def search_again(self, fire_id: int) -> bool:
        """Misplaced and not yet found again: its floor deserves one more search."""
        return self.misplaced(fire_id) and fire_id not in self.found_again_once
