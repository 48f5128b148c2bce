"""When to stop pumping: the thermal camera's CheckFire answers, judged the same way by every water task.

Why a shared judge: a single "no fire" answer is not evidence that a fire is out (the frame filter of the
detector drops for a frame, the fire leaves the view for a moment, and a nearly quenched heater falls
under the detection threshold while it still needs water). Water keeps flowing while the answers say
"cold" C.COLD_CHECKS times in a row, and "cold" counts only after the fire was seen hot at least once
while pumping (a fire never in sight is not a fire put out).
"""
from __future__ import annotations

import math
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


class WaterMeter:
    """Litres one robot put into a fire during one task run: the drops of its tank level while pumping,
    each weighted by the share of the jet believed to enter the hole (see HoleCentering.hit_share).

    Why: a fire being filled cools down in the thermal image and reads cold for its last few per cent
    (flames under the detector's 50 degC). When the tank runs dry before the cold answers came while water
    still flowed, "cold" after the last drop cannot tell a fire out from one at 98 % (seen: an indoor fire
    left at 98.7 %, marked out). Only a run that delivered a whole fire's water (`~fire_litres`) may call
    such a fire out; otherwise it stays active for a refilled robot to top up.
    """

    def __init__(self) -> None:
        self.litres = 0.0
        self._last: Optional[float] = None

    def update(self, level: float, pumping: bool, on_target: float = 1.0) -> None:
        """One tank reading (litres; NaN unknown), whether the pump ran since the last one and which share
        (0-1) of that water is believed to have gone in (the aim; 1 for a robot without a hole to aim at)."""
        if not math.isfinite(level):
            return
        if pumping and self._last is not None and level < self._last:
            self.litres += (self._last - level) * min(1.0, max(0.0, on_target))
        self._last = level

    def covers(self, fire_litres: float) -> bool:
        """True when this run alone delivered what a whole fire needs."""
        return self.litres >= fire_litres


def dry_tank_verdict(cold: ColdConfirmation, meter: WaterMeter, fire_litres: float,
                     answer: Callable[[], Optional[bool]], sleep: Callable[[float], None]) -> tuple:
    """(out, why) for a fire whose robot's tank ran dry before the cold answers: the fire is out only when it
    reads cold once the last water settled and this run delivered a whole fire's water (see WaterMeter)."""
    if not cold.settle(answer, sleep):
        return False, 'still hot, tank empty'
    if meter.covers(fire_litres):
        return True, f'cold after {meter.litres:.2f} L in'
    return False, (f'reads cold after the last water, but only {meter.litres:.2f} L went in before the tank ran dry '
                   f'(< {fire_litres:.2f} L a fire takes): it may be just short of full, left for a top-up')
