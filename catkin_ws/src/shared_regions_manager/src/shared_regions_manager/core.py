"""Shared-region manager (pure): 3D boxes of airspace reserved by agents.

Why: two UAVs must never share airspace. Every agent reserves the box it is about to fly through (and a
column for take-off and landing) before moving; a request that overlaps a box of another agent is
refused, and the agent waits and asks again.

Semantics (as the original `ask_for_region` / `free_regions`):
- `ask(agent_id, label, box)`: granted when the box overlaps no box owned by *another* agent; a granted
  box replaces the agent's previous box under the same label. Overlapping one's own boxes is allowed.
- `free(agent_id, label, free_all)`: drops the agent's box under label, or all its boxes.
"""
from __future__ import annotations

import math
import threading
from typing import Dict, Optional, Tuple

import numpy as np

from mbzirc_agents.geometry import Box, boxes_overlap, make_box


class RegionManager:
    """Holds the reserved boxes of every agent; thread-safe (service callbacks run in threads)."""

    def __init__(self) -> None:
        self._regions: Dict[Tuple[str, str], Box] = {}
        self._lock = threading.Lock()

    def ask(self, agent_id: str, label: str, min_corner, max_corner) -> Tuple[bool, str]:
        """Try to reserve the box; returns (granted, reason in words)."""
        if not agent_id:
            return False, 'empty agent_id'
        values = list(min_corner) + list(max_corner)
        if not all(math.isfinite(v) for v in values):
            return False, 'box has NaN or infinite corners'
        box = make_box(min_corner, max_corner)
        with self._lock:
            for (owner, other_label), other in self._regions.items():
                if owner != agent_id and boxes_overlap(box, other):
                    return False, f'overlaps region "{other_label}" of {owner}'
            self._regions[(agent_id, label)] = box
        return True, 'granted'

    def free(self, agent_id: str, label: str = '', free_all: bool = False) -> bool:
        """Free one region (or all of the agent's); True when something was freed."""
        with self._lock:
            if free_all:
                keys = [k for k in self._regions if k[0] == agent_id]
            else:
                keys = [k for k in self._regions if k == (agent_id, label)]
            for k in keys:
                del self._regions[k]
        return bool(keys)

    def regions(self) -> Dict[Tuple[str, str], Box]:
        """A copy of every reserved box, keyed by (agent_id, label)."""
        with self._lock:
            return {k: (v[0].copy(), v[1].copy()) for k, v in self._regions.items()}

    def owner_at(self, point) -> Optional[str]:
        """The agent whose box contains point, if any (for debugging and tests)."""
        p = np.asarray(point, dtype=float)
        with self._lock:
            for (owner, _), (lo, hi) in self._regions.items():
                if np.all(p >= lo) and np.all(p <= hi):
                    return owner
        return None
