"""Shared-region manager (pure): 3D boxes of airspace reserved by agents.

Why: two UAVs must never share airspace. Every agent reserves the box it is about to fly through (and a
column for take-off and landing) before moving; a request that overlaps a box of another agent is
refused, and the agent waits and asks again.

Semantics (as the original `ask_for_region` / `free_regions`):
- `ask(agent_id, label, box)`: granted when the box overlaps no box owned by *another* agent; a granted
  box replaces the agent's previous box under the same label. Overlapping one's own boxes is allowed.
- `free(agent_id, label, free_all)`: drops the agent's box under label, or all its boxes.

Rules added because the table is shared by every robot and trusted by all of them (issue 20):
- **Who may free**: a box is freed only by the node that reserved it, by a node in the agent's own
  namespace (`/mbzirc2020_<agent_id>/...`: a respawned agent keeps its name), or by a supervisor (the
  central unit frees the boxes of a crashed robot). `caller=None` (in-process use, tests) is trusted.
  Nothing else can free another agent's boxes, `free_all` included.
- **Unknown agents lease their boxes**: an agent id that is not one of the mission's robots
  (`known_agents`) holds a box only `unknown_lease_s` after its last granted request, so a `ghost`
  reservation of the whole arena (a stale tool, a test, a typo) blocks the UAVs for at most that long
  instead of for good. A robot's boxes never expire by time: a robot that went silent is still up there
  (safety first); the central unit frees them when it declares the robot dead.
- **Bounded table**: at most `max_labels_per_agent` boxes per agent and `max_agents` agents holding
  boxes; a request beyond that is refused with the reason (a flood of labels cannot grow memory nor make
  every request slower without limit).
- **Persistent** (`to_state` / `load_state`, the node writes them to a state file): a respawned manager
  keeps every reservation, so two UAVs are never both granted the same airspace across a crash.
- **Deadlocks are broken** (`deadlock()`, rules in deadlock.py): the refused requests of the robots that
  are still asked for are kept (not the unknown agents'); when they form a wait-for cycle with the boxes
  held (each one's request overlaps the next one's hold) for `deadlock_after_s`, the lowest-priority robot
  of the cycle is named to leave the box the robot waiting for it asked for. An order is not repeated for
  `yield_retry_s`, nor is another robot of the same cycle named meanwhile unless the victim declined.
  When the cycle still stands after that, the robot of it named fewer times yet is named first (ties: the
  lowest priority), so the robots of a standing cycle take turns: an accepted order may not be carried
  out (the victim finds no step granted), and asking the same robot again and again never helped
  (realistic seed 108: UAV 2 accepted 18 orders in 360 s, none carried out, UAV 1 was never asked).
  The turns are forgotten `3 x yield_retry_s` after a pair's last order: a new cycle starts from the
  priority again.
- **A long wait for an idle holder** (no cycle): a robot refused for `idle_yield_after_s` by boxes of a
  robot that waits for nothing asks that robot to leave (deadlock.idle_holder_order; same retry rule). Why:
  the cycle rule never fires when the holder does not wait (a UAV hovering with no work over another's
  way); an idle UAV may step aside, a working one declines.
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass
from typing import Any, Callable, Dict, Iterable, List, Optional, Tuple

import numpy as np

from mbzirc_arena.boxes import Box, boxes_overlap, make_box

from .deadlock import Wait, YieldOrder, find_cycle, idle_holder_order, ranked_priority, yield_candidates

ROBOT_NS = '/mbzirc2020_{}'


@dataclass
class Reservation:
    """One reserved box and who reserved it."""
    box: Box
    caller: str = ''              # node name that asked ('' when unknown)
    granted_at: float = 0.0       # monotonic (wall) time of the last granted request


@dataclass
class Refused:
    """A robot's refused request, while it keeps asking for it."""
    box: Box
    since: float                  # wait_clock time of the first refusal of this box
    last: float                   # wait_clock time of the latest refusal


class RegionManager:
    """Holds the reserved boxes of every agent; thread-safe (service callbacks run in threads).

    Args:
        known_agents: agent ids of the mission's robots (None: every agent is a robot, nothing leases).
        supervisors: node names allowed to free any agent's boxes.
        unknown_lease_s: seconds an unknown agent holds a box after its last granted request.
        max_labels_per_agent, max_agents: the table's bounds.
        clock: monotonic seconds (injectable for tests).
        priority: agent ids, highest priority first (default: known_agents in their order); the lowest of
            a deadlock's cycle steps aside.
        deadlock_after_s: how long a cycle must stand before a robot is told to step aside.
        waiting_fresh_s: a refused request not asked again for this long no longer waits (agents retry
            at 2 Hz).
        yield_retry_s: an order is not repeated (nor another robot of its cycle named) for this long.
        idle_yield_after_s: a robot refused this long by a robot that waits for nothing asks it to leave.
        wait_clock: seconds for the waits (default: clock; the node gives ROS time, as the agents retry
            in ROS time).
    """

    def __init__(self, known_agents: Optional[Iterable[str]] = None, supervisors: Iterable[str] = ('/central_unit',),
                 unknown_lease_s: float = 10.0, max_labels_per_agent: int = 16, max_agents: int = 32,
                 clock: Callable[[], float] = time.monotonic, priority: Optional[Iterable[str]] = None,
                 deadlock_after_s: float = 2.0, waiting_fresh_s: float = 2.0, yield_retry_s: float = 20.0,
                 wait_clock: Optional[Callable[[], float]] = None, idle_yield_after_s: float = 15.0) -> None:
        self._regions: Dict[Tuple[str, str], Reservation] = {}
        self._lock = threading.Lock()
        self.known = None if known_agents is None else {str(a) for a in known_agents}
        self.supervisors = set(supervisors)
        self.lease_s = float(unknown_lease_s)
        self.max_labels = int(max_labels_per_agent)
        self.max_agents = int(max_agents)
        self.clock = clock
        self.version = 0              # bumped at every change (the node saves when it moved)
        self.priority = ranked_priority(priority, known_agents)
        self.deadlock_after_s = float(deadlock_after_s)
        self.waiting_fresh_s = float(waiting_fresh_s)
        self.yield_retry_s = float(yield_retry_s)
        self.idle_yield_after_s = float(idle_yield_after_s)
        self.wait_clock = wait_clock or clock
        self._refused: Dict[Tuple[str, str], Refused] = {}
        self._orders: Dict[Tuple[str, str], Tuple[float, bool]] = {}   # (victim, winner) -> (time, declined)
        self._turns: Dict[Tuple[str, str], Tuple[int, float]] = {}      # (victim, winner) -> (orders, last)

    # ---- rules ------------------------------------------------------------------------------------
    def is_known(self, agent_id: str) -> bool:
        return self.known is None or agent_id in self.known

    def may_free(self, caller: Optional[str], agent_id: str, res: Reservation) -> bool:
        """Whether node `caller` may free `agent_id`'s reservation `res` (see the module docstring)."""
        if caller is None or caller in self.supervisors:
            return True
        if res.caller and caller == res.caller:
            return True
        return caller.startswith(ROBOT_NS.format(agent_id) + '/')

    def _expire(self) -> List[Tuple[str, str]]:
        """Drop the boxes of unknown agents whose lease ran out (call with the lock held)."""
        now = self.clock()
        gone = [k for k, r in self._regions.items()
                if not self.is_known(k[0]) and now - r.granted_at > self.lease_s]
        for k in gone:
            del self._regions[k]
        if gone:
            self.version += 1
        return gone

    # ---- requests -----------------------------------------------------------------------------------
    def ask(self, agent_id: str, label: str, min_corner, max_corner, caller: Optional[str] = None
            ) -> Tuple[bool, str]:
        """Try to reserve the box; returns (granted, reason in words)."""
        if not agent_id:
            return False, 'empty agent_id'
        values = list(min_corner) + list(max_corner)
        if not all(math.isfinite(v) for v in values):
            return False, 'box has NaN or infinite corners'
        box = make_box(min_corner, max_corner)
        key = (agent_id, label)
        with self._lock:
            self._expire()
            for (owner, other_label), other in self._regions.items():
                if owner != agent_id and boxes_overlap(box, other.box):
                    self._note_refused(key, box)
                    return False, f'overlaps region "{other_label}" of {owner}'
            self._refused.pop(key, None)
            if key not in self._regions:
                labels = sum(1 for a, _ in self._regions if a == agent_id)
                if labels >= self.max_labels:
                    return False, f'agent {agent_id} already holds {labels} regions (max {self.max_labels})'
                agents = {a for a, _ in self._regions}
                if agent_id not in agents and len(agents) >= self.max_agents:
                    return False, f'{len(agents)} agents already hold regions (max {self.max_agents})'
            self._regions[key] = Reservation(box, caller or '', self.clock())
            self.version += 1
        return True, 'granted' if self.is_known(agent_id) else f'granted (unknown agent: {self.lease_s:.0f} s lease)'

    def _note_refused(self, key: Tuple[str, str], box: Box) -> None:
        """Remember a robot's refused request (call with the lock held); a new box restarts its wait."""
        if not self.is_known(key[0]):
            return
        now = self.wait_clock()
        old = self._refused.get(key)
        same = old is not None and all(np.allclose(a, b, atol=0.05) for a, b in zip(old.box, box))
        fresh = old is not None and now - old.last <= self.waiting_fresh_s
        self._refused[key] = Refused(box, old.since if same and fresh else now, now)
        if len(self._refused) > self.max_labels * self.max_agents:   # bounded: labels invented in a loop
            self._refused = {k: r for k, r in self._refused.items() if now - r.last <= self.waiting_fresh_s}

    def deadlock(self) -> Optional[YieldOrder]:
        """The order that breaks a standing wait-for cycle (module docstring), or None.

        The order counts as given: the caller reports the victim's answer with `yield_answer`."""
        now = self.wait_clock()
        with self._lock:
            waits: Dict[str, Wait] = {}
            waited: Dict[str, float] = {}
            latest_first = sorted(self._refused.items(), key=lambda kv: (kv[0][0], -kv[1].last, kv[0][1]))
            for (agent, label), r in latest_first:           # an agent waits for its latest request
                if now - r.last > self.waiting_fresh_s or now - r.since < self.deadlock_after_s or agent in waits:
                    continue
                blockers = tuple(sorted(k for k, res in self._regions.items()
                                        if k[0] != agent and boxes_overlap(r.box, res.box)))
                waits[agent] = Wait(agent, label, (r.box[0].copy(), r.box[1].copy()), blockers)
                waited[agent] = now - r.since
            self._refused = {k: r for k, r in self._refused.items() if now - r.last <= self.waiting_fresh_s}
            cycle = find_cycle(waits)
            if cycle is None:
                orders = [o for o in idle_holder_order(waits, waited, self.idle_yield_after_s)
                          if self.is_known(o.victim)]
                return self._issue(orders, now)
            self._turns = {pair: v for pair, v in self._turns.items() if now - v[1] < 3.0 * self.yield_retry_s}
            orders = sorted(yield_candidates(cycle, self.priority),     # stable: priority among equals
                            key=lambda o: self._turns.get((o.victim, o.winner), (0, now))[0])
            recent = {pair: v for pair, v in self._orders.items() if now - v[0] < self.yield_retry_s}
            self._orders = recent
            if any(not declined for (victim, winner), (_, declined) in recent.items()
                   if any(o.victim == victim and o.winner == winner for o in orders)):
                return None                   # a robot of this cycle is stepping aside: give it time
            return self._issue(orders, now)

    def _issue(self, orders: List[YieldOrder], now: float) -> Optional[YieldOrder]:
        """The first of orders not given within yield_retry_s, recorded as given (call with the lock held)."""
        self._orders = {pair: v for pair, v in self._orders.items() if now - v[0] < self.yield_retry_s}
        for order in orders:
            pair = (order.victim, order.winner)
            if pair not in self._orders:
                self._orders[pair] = (now, False)
                self._turns[pair] = (self._turns.get(pair, (0, now))[0] + 1, now)
                return order
        return None

    def yield_answer(self, order: YieldOrder, accepted: bool) -> None:
        """The victim's answer: a declined order lets the next robot of the cycle be named."""
        with self._lock:
            if not accepted:
                self._orders[(order.victim, order.winner)] = (self.wait_clock(), True)

    def free(self, agent_id: str, label: str = '', free_all: bool = False, caller: Optional[str] = None
             ) -> Tuple[bool, str]:
        """Free one region (or all of the agent's); (True when something was freed, reason in words).
        Refused as a whole when `caller` may not free one of them."""
        with self._lock:
            self._expire()
            keys = [k for k in self._regions if k[0] == agent_id and (free_all or k[1] == label)]
            denied = [k for k in keys if not self.may_free(caller, agent_id, self._regions[k])]
            if denied:
                return False, (f'{caller} may not free the regions of agent {agent_id} '
                               f'(reserved by {self._regions[denied[0]].caller or "?"})')
            for k in keys:
                del self._regions[k]
            if keys:
                self.version += 1
        return bool(keys), f'freed {len(keys)}' if keys else 'nothing to free'

    def expire(self) -> List[Tuple[str, str]]:
        """Drop the expired leases now (the node calls it periodically); returns what was dropped."""
        with self._lock:
            return self._expire()

    # ---- views --------------------------------------------------------------------------------------
    def regions(self) -> Dict[Tuple[str, str], Box]:
        """A copy of every reserved box, keyed by (agent_id, label)."""
        with self._lock:
            return {k: (v.box[0].copy(), v.box[1].copy()) for k, v in self._regions.items()}

    def owner_at(self, point) -> Optional[str]:
        """The agent whose box contains point, if any (for debugging and tests)."""
        p = np.asarray(point, dtype=float)
        with self._lock:
            for (owner, _), r in self._regions.items():
                lo, hi = r.box
                if np.all(p >= lo) and np.all(p <= hi):
                    return owner
        return None

    # ---- persistence ----------------------------------------------------------------------------------
    def to_state(self) -> Dict[str, Any]:
        """Every reservation as plain JSON-able data (see `load_state`)."""
        with self._lock:
            return {'regions': [{'agent': a, 'label': l, 'min': [float(v) for v in r.box[0]],
                                 'max': [float(v) for v in r.box[1]], 'caller': r.caller}
                                for (a, l), r in sorted(self._regions.items())]}

    def load_state(self, state: Dict[str, Any]) -> int:
        """Replace the table with `to_state`'s output (an unknown agent's lease restarts now); ValueError
        (table unchanged) when anything is malformed or two agents' boxes overlap. Returns the count."""
        try:
            table: Dict[Tuple[str, str], Reservation] = {}
            for d in state['regions']:
                lo, hi = [float(v) for v in d['min']], [float(v) for v in d['max']]
                if len(lo) != 3 or len(hi) != 3 or not all(map(math.isfinite, lo + hi)):
                    raise ValueError(f'region {d.get("agent")}/{d.get("label")}: bad corners')
                agent, label = str(d['agent']), str(d['label'])
                if not agent:
                    raise ValueError('region without agent')
                table[(agent, label)] = Reservation(make_box(lo, hi), str(d.get('caller') or ''), self.clock())
        except (KeyError, TypeError) as e:
            raise ValueError(f'malformed regions state: {type(e).__name__}: {e}') from e
        items = list(table.items())
        for i, ((a, la), ra) in enumerate(items):
            for (b, lb), rb in items[i + 1:]:
                if a != b and boxes_overlap(ra.box, rb.box):
                    raise ValueError(f'regions {a}/{la} and {b}/{lb} overlap')
        with self._lock:
            self._regions = table
            self.version += 1
        return len(table)
