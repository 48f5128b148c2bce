"""The boxes a robot reserves, grown by the error of its reported pose (pure geometry).

Why: a box is built around where the robot *reports* to be, but on standard GNSS (the trial penalised RTK)
the reported pose is off the true one by a bias of the order of a metre that wanders slowly. Two boxes that
touch keep the two reported poses apart by the boxes' own margins (2 m with the defaults), but the true poses
only by that much less the two errors. Seen under realistic uncertainty (seed 107, t 384 s): UAV 3 hovered
2.4 m above UAV 2's reported arrival point, its hold box clear of UAV 2's go-to box by 0.3 m, and the true
UAVs were 0.83 m apart (UAV 2 really 0.9 m higher, UAV 3 0.8 m lower than reported).

Rule: every box is grown on each side by the per-axis error a team allows for one reported pose
(`~pose_error_margin` in x and y, `~pose_error_margin_z` in z), so that two granted boxes keep the true
poses apart by the boxes' own margins as long as each robot's error stays within it. Boxes anchored on the
ground (`GROUND_ANCHORED`: the take-off and landing columns over the home pads) grow in z only: their
x, y come from the pads, surveyed before the trial, not from GNSS, and the pads are 2.6-3.3 m apart, so
columns grown sideways would overlap the neighbours' parked boxes for as long as those stay landed (a
take-off or a landing refused for good). The parked box does not grow at all: a landed UAV stands on its
pad, on the ground (its box reaches ~parked_height above the ground). So a UAV's own boxes clear the parked
boxes from 2 m + hold box + pose error up: take-offs before landing again (~reland_height) and the flight
home (~cruise_altitude) go at least that high (3.5 m; 4 m by default, for the height held).

The hold box at the top of the take-off column is placed over the pad too (x, y of the column, z of the
take-off's target), grown in z only: grown sideways around the reported pose it overlapped the neighbours'
take-off columns, pads 2 m apart in x, and two UAVs taking off together each waited for ever for its hold
(realistic seed 107 with the first version of this rule: UAVs 1 and 2 the whole trial). Their transit
altitudes keep them apart there (mbzirc_central_unit ALTITUDE_STEP).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from mbzirc_arena.boxes import Box

# labels of the boxes placed on a home pad (or where a robot stands), not on the reported pose in the air
PARKED = 'parked'
GROUND_ANCHORED = (PARKED, 'take_off', 'land')


def pose_error_pad(label: str, margin_xy: float, margin_z: float, over_pad: bool = False) -> np.ndarray:
    """The metres (x, y, z) added on each side of our box `label` for the error of our reported pose;
    over_pad: the box's x, y are a pad's (the hold at the top of the take-off column), not a GNSS fix."""
    if label == PARKED:
        return np.zeros(3)         # on the pad, on the ground: nothing of it comes from GNSS
    xy = 0.0 if label in GROUND_ANCHORED or over_pad else max(0.0, float(margin_xy))
    return np.array([xy, xy, max(0.0, float(margin_z))])   # a negative margin would shrink or invert boxes


def grown(box: Box, pad: Sequence[float]) -> Box:
    """box grown by pad (x, y, z) on each side."""
    pad = np.asarray(pad, dtype=float)
    return np.asarray(box[0], dtype=float) - pad, np.asarray(box[1], dtype=float) + pad
