"""When to stop pumping: the thermal camera's CheckFire answers, judged the same way by every water task.

Why a shared judge: a single "no fire" answer is not evidence that a fire is out (the frame filter of the
detector drops for a frame, the fire leaves the view for a moment, and a nearly quenched heater falls
under the detection threshold while it still needs water). Water keeps flowing while the answers say
"cold" C.COLD_CHECKS times in a row, and "cold" counts only after the fire was seen hot at least once
while pumping (a fire never in sight is not a fire put out).
"""
from __future__ import annotations

from typing import Optional

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


def dry_tank_verdict(cold: ColdConfirmation) -> tuple:
    """(out, why) for a fire whose robot's tank ran dry: out only when it already read cold `checks` times in
    a row while water still flowed into it.

    Why not "cold after the last drop": a fire being filled cools down in the thermal image and reads cold
    for its last part (how large a part depends on the wall it sits on and the detector's contrast test),
    and how much water a fire needs is unknown (0.8-1.3x nominal in the real arena): no count of litres
    pumped can stand in for the sensing. A fire left cold but unconfirmed stays active for a refilled
    robot, whose water on a fire that reads cold from the start confirms it (see the tasks).
    """
    if cold.out:
        return True, 'cold with water flowing'
    return False, (f'the tank ran dry before {cold.checks} cold answers in a row with water flowing '
                   f'({cold.cold_in_row} so far): left for a top-up')
