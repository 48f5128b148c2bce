"""When to stop pumping: the thermal camera's CheckFire answers, judged the same way by every water task.

Why a shared judge: a single "no fire" answer is not evidence that a fire is out (the frame filter of the
detector drops for a frame, the fire leaves the view for a moment, and a nearly quenched heater falls
under the detection threshold while it still needs water). Water keeps flowing while the answers say
"cold" C.COLD_CHECKS times in a row, and "cold" counts only after the fire was seen hot at least once
while pumping (a fire never in sight is not a fire put out).
"""
from __future__ import annotations

from typing import Callable, Optional

from .. import constants as C


class ColdConfirmation:
    """Feeds on CheckFire answers (True hot, False cold, None no answer); says when the fire is out."""

    def __init__(self, checks: int = C.COLD_CHECKS) -> None:
        self.checks = checks
        self.cold_in_row = 0
        self.seen_hot = False

    def update(self, hot: Optional[bool]) -> bool:
        """One answer in; True once the fire was hot and then cold `checks` times in a row."""
        if hot:
            self.seen_hot, self.cold_in_row = True, 0
        elif hot is False and self.seen_hot:
            self.cold_in_row += 1
        # None (detector silent): no evidence either way, the count stays
        return self.out

    @property
    def out(self) -> bool:
        return self.seen_hot and self.cold_in_row >= self.checks

    def settle(self, answer: Callable[[], Optional[bool]], sleep: Callable[[float], None],
               period: float = 0.5) -> bool:
        """After the tank ran dry: keep asking (up to 2 x `checks` answers, `period` s apart) whether the
        last water put the fire out; a fire still filtering its last hot frames must not count as "still
        hot"."""
        for _ in range(2 * self.checks):
            if self.update(answer()):
                return True
            sleep(period)
        return self.out
