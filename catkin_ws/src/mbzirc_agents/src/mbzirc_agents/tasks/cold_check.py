"""When is a fire out: the thermal camera's CheckFire answers, judged the same way by every water task.

The rule: a fire is out only when (a) the robot saw it hot from where it waters it, (b) water then flowed
at it, and (c) it then read cold C.COLD_CHECKS times in a row, each with water flowing at it from there.
A "no fire" answer alone is no evidence: the detector's frame filter drops for a frame, the robot looks
at the wall beside the fire (mission seed 3: a fire at 63 % was reported out by a robot that never saw it
hot from its watering pose), the pump runs dry or fails, and a nearly quenched heater falls under the
detection threshold while it still needs water. The tasks say whether water flowed at the fire
(`watered`: the pump on, the tank level dropping (`WaterFlow`), the robot still where it saw it hot);
this module judges. Indoors (tasks/indoor.py) the answers that count come after a soak with the pump off
(a fire still burning shows again without water, and the count then costs no water): `watered` there
means the robot still looks from where it watered.
"""
from __future__ import annotations

import math
from typing import Optional

from .. import constants as C

FLOW_WINDOW = 1.5   # s: water flows when the tank level dropped this recently (the level comes at a few Hz)
NO_FLOW_TIME = 4.0  # s with the pump on and the tank level still: no water flows (a fault)
NOT_SEEN_HOT = 'not seen hot from the watering pose: not judged out'


class ColdConfirmation:
    """Feeds on CheckFire answers (True hot, False cold, None no answer); says when the fire is out."""

    def __init__(self, checks: int = C.COLD_CHECKS) -> None:
        self.checks = checks
        self.cold_in_row = 0
        self.seen_hot = False

    def update(self, hot: Optional[bool], watered: bool = True) -> bool:
        """One answer in; True once the fire was hot and then cold `checks` times in a row.

        `watered`: water flowed at the fire from where it was seen hot, up to this answer. A cold answer
        without it ends the row (it says "not looking" or "no water" as much as "out"); a hot one always
        restarts it (the fire still needs water)."""
        if hot:
            self.seen_hot, self.cold_in_row = True, 0
        elif hot is False and self.seen_hot:
            self.cold_in_row = self.cold_in_row + 1 if watered else 0
        # None (detector silent): no evidence either way, the count stays
        return self.out

    def restart(self) -> None:
        """The row of cold answers starts again (the conditions of the answers that count changed)."""
        self.cold_in_row = 0

    @property
    def out(self) -> bool:
        return self.seen_hot and self.cold_in_row >= self.checks


class WaterFlow:
    """Whether water is flowing: the tank level (the robot's flow meter) dropped within `window` s.

    Why the level and not the pump command: a pump that was told to start may not move water (a failed
    actuator, an empty tank), and cold answers then say nothing about the fire."""

    def __init__(self, now: float, window: float = FLOW_WINDOW) -> None:
        self.window = window
        self.since = now                 # when watching began (the pump was started)
        self.level: Optional[float] = None
        self.last_drop: Optional[float] = None

    def update(self, level: float, now: float) -> bool:
        """A tank level reading in (NaN: none); True while water flows."""
        if math.isfinite(level):
            if self.level is not None and level < self.level:
                self.last_drop = now
            self.level = level
        return self.flowing(now)

    def flowing(self, now: float) -> bool:
        return self.last_drop is not None and now - self.last_drop <= self.window

    def dry_for(self, now: float) -> float:
        """Seconds since water was last seen flowing (or since watching began)."""
        return now - (self.since if self.last_drop is None else self.last_drop)

    def stalled(self, now: float, fire_id: int) -> Optional[str]:
        """Why the water task must stop when the pump has moved no water for NO_FLOW_TIME, else None."""
        if self.dry_for(now) <= NO_FLOW_TIME:
            return None
        level = f'{self.level:.2f} L' if self.level is not None else 'unknown (no reading)'
        return (f'no water flows: the tank level stayed at {level} for {self.dry_for(now):.0f} s with the pump '
                f'on; fire {fire_id} not judged out')


class Soak:
    """The soak: the first cold answer (with water flowing) after the fire was seen hot does not start the
    cold check; the robot keeps pumping, on its frozen aim, a share `fraction` of the litres this pour had
    put in when the fire first read cold (at least `min_time` s), and only then counts cold answers.

    Why: a fire that no longer stands out in the thermal image may still burn. The detector's contrast test
    drops a nearly quenched fire (realistic missions: no more sightings at about 85 % watered), a limit of
    real thermal cameras as much as of the simulated one; the cold check's few seconds on a jet no longer
    corrected by sightings then let the GNSS drift move it off the hole, and fires at 87 % and 99.3 % were
    reported out. Firefighters soak past the point where the fire stops showing; how far is the team's
    choice (~soak_fraction, ~soak_min_time), not a simulator number. A hot answer during the soak ends it:
    the fire still shows, the robot aims on it again, and its next cold answer starts a new soak."""

    def __init__(self, fraction: float, min_time: float) -> None:
        self.fraction, self.min_time = fraction, min_time
        self.end_litres: Optional[float] = None      # pumped litres (of this pour) that end the soak
        self.end_time: Optional[float] = None
        self.done = False

    @property
    def soaking(self) -> bool:
        return self.end_litres is not None and not self.done

    def share_done(self, pumped: float) -> float:
        """Share (0-1) of the soak's litres pumped: pumped litres of this pour, the soak begun at
        end_litres / (1 + fraction); 0 before it began."""
        if self.end_litres is None:
            return 0.0
        begun = self.end_litres / (1.0 + self.fraction)
        return max(0.0, min(1.0, (pumped - begun) / max(1e-9, self.end_litres - begun)))

    def update(self, hot: Optional[bool], watered: bool, pumped: float, now: float) -> Optional[bool]:
        """One CheckFire answer in, with the litres this pour pumped so far; the answer the cold check may
        count: cold answers become None (no evidence) until the soak is over."""
        if hot:
            self.end_litres, self.end_time, self.done = None, None, False
            return hot
        if hot is None:
            return None
        if self.end_litres is None:
            if not watered:
                return hot                           # no water at it: the cold check discards it anyway
            self.end_litres = pumped * (1.0 + self.fraction)
            self.end_time = now + self.min_time
        if not self.done and pumped >= self.end_litres and now >= self.end_time:
            self.done = True
        return hot if self.done else None


def dry_tank_verdict(cold: ColdConfirmation) -> tuple:
    """(out, why) for a fire whose robot's tank ran dry: out only when it already read cold `checks` times in
    a row while water still flowed into it.

    Why not "cold after the last drop": a fire being filled cools down in the thermal image and reads cold
    for its last part (how large a part depends on the wall it sits on and the detector's contrast test),
    and how much water a fire needs is unknown (0.8-1.3x nominal in the real arena): no count of litres
    pumped can stand in for the sensing. A fire left cold but unconfirmed stays active for a refilled
    robot, which judges it out only once it saw it hot again and watered it cold (see the tasks).
    """
    if cold.out:
        return True, 'cold with water flowing'
    return False, (f'the tank ran dry before {cold.checks} cold answers in a row with water flowing '
                   f'({cold.cold_in_row} so far): left for a top-up')
