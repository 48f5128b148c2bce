"""PoseSource: where an agent's pose comes from, the UAL's or the indoor localization's, by one rule.

Why: with no GNSS indoors (ual_sim's `gnss.denied_indoors`) the UAL's reported pose dead-reckons and drifts
(half a metre in 30 s of hovering), while indoor_localization's `localization/pose` (the robot's
hector_mapping pose anchored by the last GNSS fixes and refined by the building outline) stays within a few
centimetres. The tasks must then navigate on the latter, and say so when neither can be trusted.

The rule (`choose`, evaluated at every UAL pose):
- the UAL reports a GNSS fix (`ual/gnss_status` STATUS_FIX, or no status heard yet) -> the UAL pose (`ual`);
- no fix, and the localization valid (`localization/source` says `slam` and a `localization/pose`, paired
  with the UAL pose of its stamp, is stamped within ~localization_timeout of now) -> `slam`;
- neither -> `none`, declared only once it has lasted ~pose_source_grace s (at a window the UAL's status and
  the localization's source race by a few milliseconds); meanwhile the previous source goes on.

Frames: the UAL flies to its targets in its own pose frame, which indoors is the dead-reckoned one. The agent
keeps `offset` = UAL pose - arena pose (horizontal; z and yaw are the UAL's in both sources: the
localization's z is the UAL's, and the UAL's yaw is the compass's, good everywhere, while the UAL's frame is
not rotated, only shifted by its drift). Its pose is the UAL pose minus the offset, and every target or hold
it sends the UAL is the arena target plus the offset. The offset is 0 on `ual`, the measured one on `slam`,
frozen on `none`; the offset applied follows the target one at most at ~pose_offset_rate m/s, so the
agent's pose does not jump when the source switches (a passage through a window measures its progress on
it). The UAL's drift moves the measured offset by a few cm/s: the robot agent sends a held set-point again
when the applied offset moved (robot_agent, FRAME_RESEND_DISTANCE).

A UAL pose that steps further than the robot can fly since the previous one (~max_speed, + FRAME_JUMP_MARGIN)
while the UAL leaves its dead reckoning (without a fix, and up to DEAD_RECKONING_AFTER_FIX s after the fix
returned: the status and the pose race) is a change of the UAL's own frame, not a move: the step goes into
the applied offset at once, so the agent's pose stays where the robot is, and the offset then glides to the
target as above (a step of the GNSS pose with a fix is the robot agent's pose-jump doubt's). Why: back outside, the
UAL's pose leaves its drifted dead reckoning for GNSS in one step; the offset applied was the drift (3.6 m
after 150 s inside) and gliding it off at 0.5 m/s put the agent's pose, and every target it sent, metres off
for seconds: explore + GNSS-denied seed 104, a UAV just out of a window flew back into its edge.
"""
from __future__ import annotations

import math
from collections import deque
from typing import Optional, Tuple

import numpy as np

from .params import AgentParams

UAL, SLAM, NONE = 'ual', 'slam', 'none'
LOCALIZATION_VALID = 'slam'     # indoor_localization's localization/source when its pose is the one to use
UAL_HISTORY = 90                # UAL poses kept to pair a localization pose with (3 s at ual_sim's 30 Hz)
FRAME_JUMP_MARGIN = 0.3         # m beyond what the robot can fly between two UAL poses: the UAL's frame changed
FRAME_JUMP_MAX_GAP = 1.0        # s: two UAL poses further apart are not compared (the robot may have moved)
DEAD_RECKONING_AFTER_FIX = 2.0  # s after the fix returned that the UAL's pose may still step off its dead reckoning


def choose(fix: bool, localization_valid: bool) -> str:
    """The rule: the UAL pose while it follows GNSS, else the localization's while valid, else none."""
    if fix:
        return UAL
    return SLAM if localization_valid else NONE


class PoseSource:
    """The agent's pose source and the offset between the UAL's frame and the arena. Not thread-safe: the
    robot agent calls it under its state lock. Times are the backend's (ROS) seconds. Its numbers are the
    agent params use_localization, localization_timeout, localization_pair_gap, pose_source_grace and
    pose_offset_rate (params.AgentParams)."""

    def __init__(self, p: AgentParams) -> None:
        self.p = p
        self.source = UAL
        self.why = 'GNSS fix'
        self.fix = True
        self.localization_source = ''
        self.measured: Optional[Tuple[float, np.ndarray]] = None   # (stamp, offset) of the last pairing
        self.applied = np.zeros(2)
        self._none_since: Optional[float] = None
        self._last_update: Optional[float] = None
        self._ual: deque = deque(maxlen=UAL_HISTORY)                 # (stamp, x, y) of UAL poses
        self.frame_jump: Optional[np.ndarray] = None                 # the last one absorbed, until taken
        self._dead_reckoning = False          # the UAL's frame may be its dead reckoning (no fix lately)
        self._fix_back_at: Optional[float] = None                   # UAL stamp when the fix was seen back

    # ---- inputs -------------------------------------------------------------------------------------------
    def on_ual(self, stamp: float, x: float, y: float) -> None:
        if self._ual and stamp < self._ual[-1][0]:
            self._ual.clear()                 # time went back (sim restart, bag loop)
        if self._dead_reckoning and self.fix:
            self._fix_back_at = stamp if self._fix_back_at is None else self._fix_back_at
            self._dead_reckoning = stamp - self._fix_back_at <= DEAD_RECKONING_AFTER_FIX
        if self._dead_reckoning and self._ual and stamp - self._ual[-1][0] <= FRAME_JUMP_MAX_GAP:
            t0, x0, y0 = self._ual[-1]
            step = np.array([x - x0, y - y0])
            if float(np.linalg.norm(step)) > self.p.max_speed * (stamp - t0) + FRAME_JUMP_MARGIN:
                self.applied = self.applied + step          # the UAL's frame moved, not the robot
                self.frame_jump = step
                self._ual.clear()             # the history is in the old frame: no pairing across the jump
        self._ual.append((stamp, x, y))

    def take_frame_jump(self) -> Optional[str]:
        """The log line of a change of the UAL's frame absorbed since the last call, or None."""
        if self.frame_jump is None:
            return None
        step, self.frame_jump = self.frame_jump, None
        return (f'ual/pose stepped ({step[0]:+.2f}, {step[1]:+.2f}) m, more than the robot can fly: the UAL\'s '
                f'frame changed (GNSS back?); the agent\'s pose kept, UAL frame - arena now '
                f'({self.applied[0]:+.2f}, {self.applied[1]:+.2f}) m, gliding towards '
                f'({self.target_offset()[0]:+.2f}, {self.target_offset()[1]:+.2f}) m')

    def on_gnss(self, fix: bool) -> None:
        self.fix = bool(fix)
        if not self.fix:
            self._dead_reckoning, self._fix_back_at = True, None

    def on_localization_source(self, text: str) -> None:
        self.localization_source = str(text)

    def on_localization_pose(self, stamp: float, x: float, y: float) -> str:
        """A localization pose (arena frame): measures the offset against the UAL pose of its stamp. Returns
        '' or why it was not used (to be logged, throttled)."""
        if not all(map(math.isfinite, (stamp, x, y))):
            return 'localization/pose: NaN or inf, ignored'
        ual = self.ual_at(stamp)
        if ual is None:
            span = f'{self._ual[0][0]:.2f}-{self._ual[-1][0]:.2f} s' if self._ual else 'none yet'
            return (f'localization/pose stamped {stamp:.2f} s: no UAL pose within '
                    f'{self.p.localization_pair_gap:.2f} s of it (UAL poses kept: {span}), ignored')
        self.measured = (stamp, ual - np.array([x, y]))
        return ''

    def ual_at(self, stamp: float) -> Optional[np.ndarray]:
        """The UAL's (x, y) at stamp, interpolated between two of its poses at most pair_gap apart (the
        newest one up to pair_gap after it); None when the history does not cover it."""
        hist, gap = self._ual, self.p.localization_pair_gap
        if not hist or stamp < hist[0][0] - 1e-9:
            return None
        if stamp >= hist[-1][0]:
            return np.array(hist[-1][1:]) if stamp - hist[-1][0] <= gap else None
        for (t0, x0, y0), (t1, x1, y1) in zip(reversed(list(hist)[:-1]), reversed(hist)):
            if t0 <= stamp <= t1:
                if t1 - t0 > gap:
                    return None
                w = 0.0 if t1 <= t0 else (stamp - t0) / (t1 - t0)
                return np.array([x0 + w * (x1 - x0), y0 + w * (y1 - y0)])
        return None

    # ---- the rule -----------------------------------------------------------------------------------------
    def _localization_fresh(self, now: float) -> bool:
        """A localization/pose was paired within ~localization_timeout of now."""
        return self.measured is not None and now - self.measured[0] <= self.p.localization_timeout

    def localization_pending(self, now: float) -> bool:
        """True while an indoor localization runs (its source heard) but its pose is not anchored (none
        paired within ~localization_timeout): inside, with no GNSS, there would be no trusted pose."""
        return self.p.use_localization and self.localization_source != '' and not self._localization_fresh(now)

    def localization_valid(self, now: float) -> bool:
        return (self.p.use_localization and self.localization_source == LOCALIZATION_VALID
                and self._localization_fresh(now))

    def update(self, now: float) -> Optional[str]:
        """Apply the rule at time now and move the applied offset; returns the log line of a switch, else
        None."""
        fix = self.fix or not self.p.use_localization
        wanted = choose(fix, self.localization_valid(now))
        before = self.source
        if wanted != NONE:
            self._none_since = None
            self.source = wanted
        else:
            if self._none_since is None or now < self._none_since:
                self._none_since = now
            if now - self._none_since >= self.p.pose_source_grace:
                self.source = NONE
        self.why = self._why(now)
        self._move_offset(now)
        if self.source == before:
            return None
        return (f'pose source {before} -> {self.source} ({self.why}); UAL frame - arena '
                f'({self.applied[0]:+.2f}, {self.applied[1]:+.2f}) m, towards '
                f'({self.target_offset()[0]:+.2f}, {self.target_offset()[1]:+.2f}) m')

    def _why(self, now: float) -> str:
        if self.fix:
            return 'GNSS fix' if self.p.use_localization else 'GNSS fix or not (~use_localization false)'
        if self.localization_valid(now):
            return 'no GNSS fix, localization/pose valid'
        if self.localization_source != LOCALIZATION_VALID:
            said = self.localization_source or 'nothing'
            return f'no GNSS fix and localization/source says {said}'
        if self.measured is None:
            return 'no GNSS fix and no usable localization/pose'
        return (f'no GNSS fix and localization/pose {now - self.measured[0]:.1f} s old '
                f'(> {self.p.localization_timeout:.1f} s)')

    def target_offset(self) -> np.ndarray:
        if self.source == UAL:
            return np.zeros(2)
        if self.source == SLAM and self.measured is not None:
            return self.measured[1]
        return self.applied                    # none: frozen where it was

    def _move_offset(self, now: float) -> None:
        dt = 0.0 if self._last_update is None else max(0.0, now - self._last_update)
        self._last_update = now
        step = self.target_offset() - self.applied
        n = float(np.linalg.norm(step))
        limit = self.p.pose_offset_rate * dt
        self.applied = self.applied + (step if n <= limit else step * (limit / n))

    # ---- frames -------------------------------------------------------------------------------------------
    @property
    def valid(self) -> bool:
        """False while no pose can be trusted (source none): motion commands become holds."""
        return self.source != NONE

    def to_arena(self, x: float, y: float) -> Tuple[float, float]:
        """A UAL-frame (x, y) in the arena frame."""
        return float(x - self.applied[0]), float(y - self.applied[1])

    def to_ual(self, x: float, y: float) -> Tuple[float, float]:
        """An arena (x, y) in the UAL's frame (what its go-to flies to)."""
        return float(x + self.applied[0]), float(y + self.applied[1])


__all__ = ['PoseSource', 'choose', 'UAL', 'SLAM', 'NONE', 'LOCALIZATION_VALID']
