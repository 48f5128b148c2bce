"""Deadlocks between reservations: a wait-for cycle, and which agent steps aside to break it (pure).

Why: an agent that waits for a box keeps the box it hovers in (its `hold`), so two agents can each wait
for a box that overlaps the other's hold, and neither ever moves (realistic seed 104: UAVs 2 and 3 waited
the whole trial right after take-off, each one's `go_to` overlapping the other's `hold`). Refusing such
requests is right (granting either would put two UAVs in one box); the way out is physical: one of them
leaves the box the other asked for, and then the other's request is granted.

Rules:
- The wait-for graph has an edge A -> B when A's current refused request overlaps a box B holds. Only
  requests still being asked count (an agent that stopped asking no longer waits).
- A cycle A -> B -> ... -> A is a deadlock: every agent in it waits, so no box in it is ever freed.
  Cycles are searched from the agents in sorted order, neighbours in sorted order: the same table gives
  the same cycle.
- The victim is the agent of the cycle with the lowest priority (last in the priority list; agents not in
  it come after, by id): it is asked to leave the refused box of the agent that waits for it (its
  predecessor in the cycle), the winner. When it cannot (it declines: not hovering, in a passage, no free
  place), the next-lowest is asked, and so on. When the cycle still stands after an order (accepted but
  not carried out), the robot of it named fewer times yet comes first (core.py: the robots take turns).
- No cycle, but a robot has waited `idle_yield_after` for boxes of a robot that waits for nothing (it
  hovers idle, or works where it is): that holder is asked to leave the box (`idle_holder_order`); it
  accepts only when idle (mbzirc_agents README), else it declines and the wait goes on (a working robot
  frees its boxes when its work ends).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from mbzirc_arena.boxes import Box, box_text as fmt_box


@dataclass(frozen=True)
class Wait:
    """An agent's refused request that it still asks for, and the boxes of others it overlaps."""
    agent: str
    label: str
    box: Box
    blockers: Tuple[Tuple[str, str], ...]      # (owner, label) of every other agent's box it overlaps


@dataclass(frozen=True)
class YieldOrder:
    """Break a cycle: `victim` leaves `box`, the refused request `winner_label` of `winner`."""
    victim: str
    winner: str
    winner_label: str
    box: Box
    victim_labels: Tuple[str, ...]            # the victim's boxes that overlap it
    cycle: Tuple[Wait, ...]
    idle_for: float = 0.0      # > 0: no cycle, the winner waited this long for a victim waiting for nothing

    def describe(self) -> str:
        """The cycle (or the long wait for an idle holder) and the order in words (the manager's log line)."""
        if self.idle_for > 0.0:
            return (f'{self.winner}/{self.winner_label} {fmt_box(self.box)} has waited {self.idle_for:.0f} s for '
                    f'{" and ".join(f"{self.victim}/{l}" for l in self.victim_labels)}, and {self.victim} waits for '
                    f'nothing: {self.victim} is asked to move out of it')
        waits = ', '.join(f'{w.agent}/{w.label} {fmt_box(w.box)} waits for '
                          + ' and '.join(f'{o}/{l}' for o, l in w.blockers) for w in self.cycle)
        return (f'deadlock: {waits}; {self.victim} (lowest priority) is asked to move its '
                f'{"/".join(self.victim_labels)} out of {self.winner}/{self.winner_label} {fmt_box(self.box)}')


def find_cycle(waits: Dict[str, Wait]) -> Optional[List[Wait]]:
    """The first cycle of the wait-for graph (agent -> owners of the boxes its request overlaps), or None."""
    def successors(a: str) -> List[str]:
        return sorted({o for o, _ in waits[a].blockers if o in waits and o != a})

    for start in sorted(waits):
        path, on_path = [start], {start}
        stack = [iter(successors(start))]
        while stack:
            nxt = next(stack[-1], None)
            if nxt is None:
                stack.pop()
                on_path.discard(path.pop())
                continue
            if nxt in on_path:
                return [waits[a] for a in path[path.index(nxt):]]
            path.append(nxt)
            on_path.add(nxt)
            stack.append(iter(successors(nxt)))
    return None


def yield_candidates(cycle: Sequence[Wait], priority: Sequence[str]) -> List[YieldOrder]:
    """The orders that would break the cycle, the lowest-priority victim first."""
    rank = {a: i for i, a in enumerate(priority)}
    agents = [w.agent for w in cycle]
    by_agent = {w.agent: w for w in cycle}
    orders = []
    for victim in sorted(agents, key=lambda a: (-rank.get(a, len(priority)), a)):
        winner = agents[agents.index(victim) - 1]          # its predecessor: the one waiting for it
        w = by_agent[winner]
        labels = tuple(sorted(l for o, l in w.blockers if o == victim))
        orders.append(YieldOrder(victim, winner, w.label, w.box, labels, tuple(cycle)))
    return orders


def ranked_priority(priority: Iterable[str], known: Optional[Iterable[str]]) -> List[str]:
    """The priority list as strings (the known agents in their order when none is given)."""
    given = [str(a) for a in priority or []]
    return given if given else [str(a) for a in known or []]


def idle_holder_order(waits: Dict[str, Wait], waited: Dict[str, float], after: float) -> List[YieldOrder]:
    """Orders to holders that wait for nothing, of robots that waited at least `after` s for their boxes
    (`waited`: seconds each waiting agent has waited for its request), the longest wait first."""
    orders = []
    for agent in sorted(waits, key=lambda a: (-waited.get(a, 0.0), a)):
        w, t = waits[agent], waited.get(agent, 0.0)
        if t < after:
            continue
        for owner in sorted({o for o, _ in w.blockers if o not in waits and o != agent}):
            labels = tuple(sorted(l for o, l in w.blockers if o == owner))
            orders.append(YieldOrder(owner, agent, w.label, w.box, labels, (w,), idle_for=t))
    return orders
