"""Bookkeeping of the strategy: goals in flight, what each agent did last, searches done, failures, and
which robots crashed or are broken.

.. note:: this memory only saves time: a restarted strategy starts empty and at worst repeats a search.
"""
from __future__ import annotations

from collections import Counter
from typing import Any, Optional

from . import constants as C
from .command import Command, StrategyParams
from .failure_rules import (LEG_BLOCKED, NOT_SEEN_HOT, UNSEEN_WINDOW_TRIES, WINDOW_UNSEEN, LegBackoff,
                            UnconfirmedFires, failure_kind)
from .world_model import AgentView, WorldView

PENDING_TICKS = 10  # decision ticks an agent waits for the fires its search reported
# s an agent seen ready, never seen moving, stays UNINITIALIZED before it counts as crashed (`note_crashes`):
# longer than a respawned agent reports UNINITIALIZED before it hears its UAL again (ual/state comes on a
# change and at least every 1 s: ual_sim STATE_KEEPALIVE_S), with the margin of two more of those
CRASH_CONFIRM_S = 3.0


class Bookkeeping:
    def __init__(self, params: StrategyParams) -> None:
        self.p = params
        self.facade_searches: Counter[int] = Counter()
        self.indoor_searches: Counter[tuple[int, Any]] = Counter()  # (floor, room index or "door")
        self.ground_searches = 0
        self.failures: Counter[tuple[str, str, Any]] = Counter()
        self.window_unseen: Counter[tuple[str, str, Any]] = Counter()   # failure_rules rule 3
        self.in_flight: dict[str, Command] = {}
        self.last_done: dict[str, Command] = {}
        self.finished: set[str] = set()  # agents sent home for good
        # Fire ids a search just reported, not yet in /estimated_objects: the agent waits a few ticks.
        self.pending_ids: dict[str, tuple[set[int], int]] = {}
        self.consecutive_failures: Counter[str] = Counter()
        self.seen_flying: set[str] = set()
        self.seen_ready: set[str] = set()   # agents whose UAL reported a state (not UNINITIALIZED) once
        self.crashed: set[str] = set()  # robots seen moving, now UNINITIALIZED: the simulator's crash state
        self.uninitialized_since: dict[str, float] = {}   # agents seen ready, UNINITIALIZED since then
        self.leg_backoff = LegBackoff(params.leg_blocked_backoff, params.leg_blocked_backoff_max,
                                      params.max_blocked_legs)
        self.unconfirmed = UnconfirmedFires(params.not_seen_hot_limit, params.facade_top_up_limit)
        # facade floors searched once more, whatever their count: a fire there was judged misplaced
        # (failure_rules.py); the next search of the floor that ends takes the floor off
        self.search_again: set[int] = set()
        self.notes: list[str] = []  # log lines of the failure rules, taken by the node (take_notes)
        # the room (floor, index) each agent last entered, and the room whose search found each indoor fire:
        # the way to a fire is through that room (IndoorPhase.room_to_reach), and out through that window
        self.entered: dict[str, tuple[int, Any]] = {}
        self.fire_rooms: dict[int, tuple[int, Any]] = {}
        # where each agent's last entry ended (the enter_building it succeeded, the x, y it then reported): a
        # place inside it flew to, where its way out starts when the interior is not known (transit.exit_path)
        self.way_in_end: dict[str, tuple[Command, tuple[float, float]]] = {}

    def on_sent(self, cmd: Command) -> None:
        """The node sent `cmd`: the agent is busy with it until `record`."""
        self.in_flight[cmd.agent_id] = cmd

    def record(self, cmd: Command, succeeded: bool, result: Optional[dict[str, Any]] = None,
               now: float = 0.0) -> bool:
        """Count the outcome of a command (searches done, failures); True when the agent has now failed it
        `max_failures` times on this target, or its leg was blocked `max_blocked_legs` times
        (failure_rules.py): that work is given up for this agent. `now`: sim time of the result."""
        result = result or {}
        self.in_flight.pop(cmd.agent_id, None)
        if succeeded:
            self.consecutive_failures[cmd.agent_id] = 0
            self.last_done[cmd.agent_id] = cmd
            if cmd.task in (C.EXTINGUISH_FACADE_FIRE, C.EXTINGUISH_INDOOR_FIRE):
                self.unconfirmed.note_watered_hot(cmd.target)   # the agents succeed only after watering it hot
            if result.get("fire_ids"):
                self.pending_ids[cmd.agent_id] = ({int(i) for i in result["fire_ids"]}, PENDING_TICKS)
                if cmd.task in (C.SEARCH_FACADE, C.SEARCH_INDOOR):   # they report only fires they saw hot
                    self.notes += [n for n in (self.unconfirmed.note_found(int(i), cmd.task)
                                               for i in result["fire_ids"]) if n]
                if cmd.task == C.SEARCH_INDOOR and isinstance(cmd.target, tuple) \
                        and all(isinstance(k, int) for k in cmd.target):   # a room's (floor, index)
                    for i in result["fire_ids"]:
                        self.fire_rooms.setdefault(int(i), cmd.target)
            if cmd.task == C.ENTER_BUILDING:
                self.entered[cmd.agent_id] = cmd.target
            self._count_search(cmd)
            return False
        self.last_done.pop(cmd.agent_id, None)
        key = (cmd.agent_id, cmd.task, cmd.target)
        self.failures[key] += 1
        self.consecutive_failures[cmd.agent_id] += 1
        kind = failure_kind(cmd.task, str(result.get("message", "")))
        if kind == LEG_BLOCKED:
            gave_up, note = self.leg_backoff.note(key, now)
            self.notes.append(note)
            if gave_up:
                self.failures[key] = max(self.failures[key], self.p.max_failures)
        elif kind == WINDOW_UNSEEN:
            self.window_unseen[key] += 1
            if self.window_unseen[key] >= UNSEEN_WINDOW_TRIES:
                self.failures[key] = max(self.failures[key], self.p.max_failures)
                self.notes.append(f"agent {cmd.agent_id}: its laser saw no opening wide enough at the window of "
                                  f"room {cmd.target} {self.window_unseen[key]} times: that window is given up "
                                  "by it")
        elif kind == NOT_SEEN_HOT:
            note = self.unconfirmed.note(cmd.target, cmd.agent_id, facade=cmd.task == C.EXTINGUISH_FACADE_FIRE)
            if note:
                self.notes.append(note)
                if cmd.task == C.EXTINGUISH_FACADE_FIRE and self.unconfirmed.search_again(cmd.target):
                    self.search_again.add(cmd.goal["_floor"])
        if self.failures[key] < self.p.max_failures:
            return False
        self._count_search(cmd)  # a search given up counts as one, so that the mission moves on
        if cmd.task == C.ENTER_BUILDING:   # so does a room whose window this agent gave up entering
            self.indoor_searches[cmd.target] += 1
        return True

    def take_notes(self) -> list[str]:
        """The failure rules' log lines since the last call."""
        notes, self.notes = self.notes, []
        return notes

    def backing_off(self, cmd: Command, now: float) -> bool:
        """True while `cmd` (same agent, task and target) waits out a blocked-leg back-off."""
        return self.leg_backoff.waiting((cmd.agent_id, cmd.task, cmd.target), now)

    def _count_search(self, cmd: Command) -> None:
        if cmd.task == C.SEARCH_FACADE:
            self.facade_searches[cmd.target] += 1
            self.search_again.discard(cmd.target)
        elif cmd.task == C.SEARCH_INDOOR:
            self.indoor_searches[cmd.target] += 1
        elif cmd.task == C.LOOK_FOR_GROUND_FIRES:
            self.ground_searches += 1

    def forget(self, cmd: Command) -> None:
        """A command that could not be sent (no action server yet): not in flight, not a failure."""
        if self.in_flight.get(cmd.agent_id) is cmd:
            del self.in_flight[cmd.agent_id]

    def note_way_in(self, agent_id: str, xy: tuple[float, float]) -> None:
        """The agent is at xy now: the end of its way in when its last task done was an entry not noted yet."""
        last = self.last_done.get(agent_id)
        if last is not None and last.task == C.ENTER_BUILDING and self.way_in_end.get(agent_id, (None,))[0] is not last:
            self.way_in_end[agent_id] = (last, (float(xy[0]), float(xy[1])))

    def way_in_end_of(self, agent_id: str, room: tuple[int, Any]) -> Optional[tuple[float, float]]:
        """Where the agent's last entry, into room (floor, index), ended; None when its last entry was another."""
        noted = self.way_in_end.get(agent_id)
        return noted[1] if noted is not None and noted[0].target == room else None

    def forget_agent(self, agent_id: str) -> None:
        """An agent went silent: its goal and its last task are forgotten."""
        self.in_flight.pop(agent_id, None)
        self.last_done.pop(agent_id, None)

    def broken(self, agent_id: str) -> bool:
        """An agent that cannot take off any more, or failed every task of a long row (a crashed robot
        still publishes its data_feed): it gets no more work, and owns nothing."""
        return (agent_id in self.crashed
                or self.failures[(agent_id, C.TAKE_OFF, None)] >= self.p.max_failures
                or self.consecutive_failures[agent_id] >= 2 * self.p.max_failures)

    def ok(self, a: AgentView, task: str, target: Any) -> bool:
        """False once this agent failed this task on this target too often."""
        return self.failures[(a.agent_id, task, target)] < self.p.max_failures

    def window_ok(self, a: AgentView, target: Any) -> bool:
        """enter_building through a room's window (target (floor, room)): False once this agent failed it
        ~max_failures times, or all agents together ~max_failures + 1 times. Why: a window too narrow for
        the frame (the end of an interior wall behind it, which an explored layout does not know) is the
        window's fact, and the water UAVs share one frame size; each spent three tries of 20-25 s on the same
        window (explore + GNSS-denied seed 103: facade B's floor-1 window, 140 s in all). One more try by
        another agent is left for a failure of the first agent's own (its pose, a gust)."""
        tries = sum(n for (_aid, task, tgt), n in self.failures.items() if task == C.ENTER_BUILDING and tgt == target)
        return self.ok(a, C.ENTER_BUILDING, target) and tries < self.p.max_failures + 1

    def note_crashes(self, world: WorldView) -> list[str]:
        """Agents that crashed since the last call: a robot that moved (UAV flying, UGV driving:
        FLYING_AUTO) and is UNINITIALIZED again (it lies where it fell, deaf); or one seen ready (landed)
        and UNINITIALIZED for CRASH_CONFIRM_S since. Their goal is forgotten.

        Why the second: the simulator's crash state is UNINITIALIZED whatever the robot did (a landed UAV
        struck by another robot crashes too), and a restarted central unit never saw a robot that flew
        before fly: its crash went unnoticed and its regions were never freed (central_unit.test, the crash
        of UAV 3 after the restart, when the restart came as it went home: 'the crashed UAV's regions were
        not freed'). Confirmed over CRASH_CONFIRM_S: a respawned agent says UNINITIALIZED until it hears
        its UAL."""
        new = []
        for a in world.agents.values():
            if a.ual_state != C.UAL_UNINITIALIZED:
                self.seen_ready.add(a.agent_id)
                self.uninitialized_since.pop(a.agent_id, None)
            if a.ual_state in (C.UAL_TAKING_OFF, C.UAL_FLYING_AUTO, C.UAL_FLYING_MANUAL):
                self.seen_flying.add(a.agent_id)
            elif a.ual_state == C.UAL_UNINITIALIZED and a.agent_id in self.seen_ready \
                    and a.agent_id not in self.crashed and a.alive(world.now, self.p.agent_timeout):
                since = self.uninitialized_since.setdefault(a.agent_id, world.now)
                if a.agent_id in self.seen_flying or world.now - since >= CRASH_CONFIRM_S:
                    self.crashed.add(a.agent_id)
                    self.in_flight.pop(a.agent_id, None)
                    new.append(a.agent_id)
        return new

    def waiting_for_reported_fires(self, agent_id: str, world: WorldView) -> bool:
        """True while fires the agent's last search reported have not reached /estimated_objects yet."""
        ids, ticks = self.pending_ids.get(agent_id, (set(), 0))
        if not ids or ids & set(world.fires) or ticks <= 0:
            self.pending_ids.pop(agent_id, None)
            return False
        self.pending_ids[agent_id] = (ids, ticks - 1)
        return True

    def not_ready(self, a: AgentView) -> bool:
        """True until the agent's autopilot (UAL) reported a state, e.g. while the simulator starts, or while
        its data_feed has not yet carried a pose: a goal then fails at once, and three such
        failures made the UGV give up its job (seen), and a water UAV give up refilling for the whole trial
        (ideal seed 7: three 'go_home_and_refill -> home unknown (no pose yet)' at 2 s, its tank reported
        empty before the first reading; 0.56 L left after its first fire, it hovered idle for 640 s). Only
        until its first state: UNINITIALIZED later is the crash state. Nor while the agent says it has no
        trusted pose (C.NO_TRUSTED_POSE: no GNSS fix and no valid indoor localization): a goal would fail at
        once and stop the robot backing out the way it came (explore + GNSS-denied seed 101: 7 goals in 8 s
        to a UAV whose SLAM pose had jumped, each aborted 'no trusted pose')."""
        if not a.reported or a.active_sub_state.startswith(C.NO_TRUSTED_POSE):
            return True
        if a.ual_state != C.UAL_UNINITIALIZED:
            self.seen_ready.add(a.agent_id)
            return False
        return a.agent_id not in self.seen_ready and a.agent_id not in self.seen_flying
