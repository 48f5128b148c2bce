"""Who a heartbeat comes from, and whether to believe it (pure, no ROS).

Why: a liveness signal is only worth what it proves. The central unit's heartbeat used to come from a timer
beside the work (it kept beating while the decision loop was blocked), and any Header on the topic was
believed, even one replayed from a bag of an earlier mission. Now the sender publishes it from the loop
that does the work, and names itself in `header.frame_id` with a run id:

    <node>/<mission>/<instance>      e.g. central_unit/3f2a...-run-id/9c1e04ab77d2

`mission` is the ROS master's `/run_id` (new for every roscore), `instance` is new for every start of the
sender process. `HeartbeatFilter` (on the receiving side) believes a heartbeat when:
- its mission is this mission (a bag of another mission is refused);
- its instance is the current one with a higher `seq` than the last believed (a replay of this run's
  earlier heartbeats is refused), or a new instance never seen before (the sender restarted; it then
  supersedes the old one, whose heartbeats are refused from then on).
A heartbeat without a run id (`frame_id` without '/') is believed only until the first one with a run id
(older senders, tests).
"""
from __future__ import annotations

import uuid
from typing import Optional, Set, Tuple


def new_run_id(node: str, mission: str) -> str:
    """The `frame_id` a sender stamps on its heartbeats for this start of its process."""
    return f'{node}/{mission or "-"}/{uuid.uuid4().hex[:12]}'


def parse_run_id(frame_id: str) -> Optional[Tuple[str, str, str]]:
    """(node, mission, instance), or None for a heartbeat without a run id."""
    parts = (frame_id or '').split('/')
    if len(parts) != 3 or not all(parts):
        return None
    return parts[0], parts[1], parts[2]


class HeartbeatFilter:
    """Believes or refuses heartbeats (see the module docstring).

    Args:
        mission: this mission's `/run_id` ('' : not checked).
    """

    def __init__(self, mission: str = '') -> None:
        self.mission = mission
        self.current: Optional[str] = None          # instance believed now
        self.last_seq = -1
        self.superseded: Set[str] = set()
        self.refused = 0

    def accept(self, frame_id: str, seq: int) -> Tuple[bool, str]:
        """(believed, why in words) for one heartbeat."""
        run = parse_run_id(frame_id)
        if run is None:
            if self.current is None:
                return True, 'no run id (older sender)'
            return self._refuse('no run id, but a sender with a run id is alive')
        _node, mission, instance = run
        if self.mission and mission != self.mission:
            return self._refuse(f'from another mission ({mission}, this one is {self.mission}): replayed?')
        if instance in self.superseded:
            return self._refuse(f'from instance {instance}, replaced since by {self.current}: replayed?')
        if instance == self.current:
            if seq <= self.last_seq:
                return self._refuse(f'seq {seq} not after {self.last_seq}: replayed?')
            self.last_seq = seq
            return True, 'ok'
        if self.current is not None:
            self.superseded.add(self.current)
        self.current, self.last_seq = instance, seq
        return True, f'new instance {instance}'

    def _refuse(self, why: str) -> Tuple[bool, str]:
        self.refused += 1
        return False, why
