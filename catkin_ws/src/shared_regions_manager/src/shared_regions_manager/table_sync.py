"""One numbered table: every change of the reservations is numbered, logged, saved and shown in that order,
under one lock (pure: the node passes in its save, publish and log).

Why: the fault suite kills the manager and checks that the respawned one resumed every reservation of the
last table it showed (/regions). The node used to save on each change but read the table again to publish
it, from the service threads and from its 1 Hz timer, without a common lock: a publication could show a
table other than the one on disk (a timer that read the table before an owner freed a box published it
after the free was saved and shown), and nothing told the suite which table a message showed. In one run
the last /regions before the kill still had 2/go_to, freed by UAV 2 and saved just before the kill, and the
suite reported it lost.

Rules (`TableSync`):
- a change (a granted or freed box, an expired lease) gets the next table number; under the lock its
  removed boxes are logged (`table <n>: removed a/l, ...`, before the save: a kill right after the save
  leaves the log line), then the table is saved with its number, then it is shown with its number;
- a publication (change or timer) shows the table as it is under the lock, with the number it was saved
  under: the table shown is always the table on disk, and table numbers never go back on /regions;
- a request that changes nothing (refused, nothing to free) gets no number, nothing is saved.
So a respawned manager that resumed table `S` must hold every box of a shown table `n <= S` except the ones
logged as removed by tables `n+1 .. S`; anything else is a reservation lost.
"""
from __future__ import annotations

import threading
from typing import Any, Callable, Dict, Optional, Tuple, TypeVar

T = TypeVar('T')
Key = Tuple[str, str]

REMOVED_LINE = 'region manager: table {table}: removed {keys}'


def key_text(key: Key) -> str:
    """A reservation as the suite and the logs name it: ``agent/label``."""
    return f'{key[0]}/{key[1]}'


class TableSync:
    """Numbers, logs, saves and shows the changes of `core` (a RegionManager) in one order.

    Args:
        core: the table (`version` moves at every change; `regions()`, `to_state()`).
        save: `save(state, table)` writes the state (with its number) to disk; an OSError is logged by
            the caller's save and the change is still shown (its number then says it is not on disk).
        publish: `publish(regions, table)` shows the table (None: not shown).
        log: `log(text)` for the removed boxes.
        table: the number of the table `core` holds now (a resumed table's number).
    """

    def __init__(self, core: Any, save: Callable[[Dict[str, Any], int], None],
                 publish: Optional[Callable[[Dict[Key, Any], int], None]], log: Callable[[str], None],
                 table: int = 0) -> None:
        self.core = core
        self._save = save
        self._publish = publish
        self._log = log
        self.table = int(table)
        self.lock = threading.Lock()

    def change(self, mutate: Callable[[], T]) -> T:
        """Run `mutate` (a call of the core that may change the table) and, when it changed the table,
        number, log, save and show the new table; returns what `mutate` returned."""
        with self.lock:
            version = self.core.version
            keys_before = set(self.core.regions())
            result = mutate()
            if self.core.version != version:
                self.table += 1
                regions = self.core.regions()
                removed = sorted(keys_before - set(regions))
                if removed:
                    self._log(REMOVED_LINE.format(table=self.table, keys=', '.join(map(key_text, removed))))
                self._save(self.core.to_state(), self.table)
                if self._publish is not None:
                    self._publish(regions, self.table)
            return result

    def republish(self) -> None:
        """Show the table again (the timer), with its number, never between a change and its save."""
        if self._publish is None:
            return
        with self.lock:
            self._publish(self.core.regions(), self.table)
