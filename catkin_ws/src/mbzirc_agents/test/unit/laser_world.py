"""A 2D laser for the agents' unit tests: ray casting of axis-aligned wall boxes, with the realistic profile's
range noise and NaN / inf dropouts when asked (ual_sim's numbers are not read: the test says its own).

`wall_boxes(z)` builds the outer walls of the arena model's buildings at height z, 0.2 m thick, with its
windows and doors open, shifted by `shift` (a world whose true geometry is `shift` away from the arena
model: what a robot with a GNSS bias of -shift sees).
"""
import math
from collections import deque

import numpy as np

from mbzirc_arena.c3 import ARENA

BEAMS = 720
ANGLE_MIN = -math.pi
INC = 2 * math.pi / BEAMS
THICK = 0.2


def cast(origin, yaw, boxes, noise=0.0, nan_rate=0.0, inf_rate=0.0, rng=None):
    """720 ranges (angle_min -pi, front at index 360) from origin (x, y) at yaw against boxes
    [(x0, y0, x1, y1)]; inf where no box is hit."""
    a = yaw + ANGLE_MIN + INC * np.arange(BEAMS)
    dx, dy = np.cos(a), np.sin(a)
    r = np.full(BEAMS, np.inf)
    with np.errstate(divide='ignore', invalid='ignore'):
        for x0, y0, x1, y1 in boxes:
            tx0, tx1 = (x0 - origin[0]) / dx, (x1 - origin[0]) / dx
            ty0, ty1 = (y0 - origin[1]) / dy, (y1 - origin[1]) / dy
            tn = np.maximum(np.minimum(tx0, tx1), np.minimum(ty0, ty1))
            tf = np.minimum(np.maximum(tx0, tx1), np.maximum(ty0, ty1))
            hit = (tn <= tf) & (tf > 0) & np.isfinite(tn)
            r = np.where(hit, np.minimum(r, np.maximum(tn, 0.0)), r)
    if rng is not None:
        r = r + rng.normal(0.0, 1.0, BEAMS) * np.maximum(noise * np.where(np.isfinite(r), r, 0.0), 0.005 * (noise > 0))
        u = rng.random(BEAMS)
        r[u < nan_rate] = np.nan
        r[(u >= nan_rate) & (u < nan_rate + inf_rate)] = np.inf
    return r


def wall_boxes(z, shift=(0.0, 0.0), openings=None):
    """Outer walls (boxes 0.2 m thick inside the outline) of the buildings standing at height z, with the
    openings (default: the arena model's) whose height range holds z left open, all moved by shift."""
    openings = ARENA.openings if openings is None else openings
    boxes = []
    for b in ARENA.buildings:
        x0, y0, _z0, x1, y1, top = b.box
        if z >= top:
            continue
        faces = [('y', y1 - THICK, y1, x0, x1), ('y', y0, y0 + THICK, x0, x1),
                 ('x', x0, x0 + THICK, y0, y1), ('x', x1 - THICK, x1, y0, y1)]
        for axis, lo, hi, s0, s1 in faces:
            cuts = []
            for o in openings:
                if abs(o.centre[2] - z) > o.height / 2:
                    continue
                across = o.centre[1] if axis == 'y' else o.centre[0]
                along = o.centre[0] if axis == 'y' else o.centre[1]
                if lo - 0.01 <= across <= hi + 0.01 and s0 <= along <= s1:
                    cuts.append((along - o.width / 2, along + o.width / 2))
            pieces, s = [], s0
            for c0, c1 in sorted(cuts):
                pieces.append((s, c0))
                s = c1
            pieces.append((s, s1))
            for p0, p1 in pieces:
                if p1 - p0 <= 1e-6:
                    continue
                box = (p0, lo, p1, hi) if axis == 'y' else (lo, p0, hi, p1)
                boxes.append((box[0] + shift[0], box[1] + shift[1], box[2] + shift[0], box[3] + shift[1]))
    return boxes


class LaserScene:
    """Publishes the fake UAL's laser and altimeter at 10 Hz (sim clock) into an agent: ray cast from its
    true position against `boxes` (default: the arena model's walls at its height, shifted by `shift`), with
    the realistic profile's noise and dropouts unless `noisy` is False; `blind` sends every beam NaN. Each scan
    is stamped with the sim time it was taken at; `lag` (s, or a function of that time; None from it: the scan
    is lost) delays its arrival, in order, as a loaded machine does (ROS keeps a topic's order).

    Args: be (FakeBackend), ual (FakeUal), shift (m, x, y), laser_z (m above the robot's z), z_shift (m:
    the whole world, ground included, is that much higher than the fake UAL's z frame: a vertical GNSS bias).
    """

    def __init__(self, be, ual, shift=(0.0, 0.0), laser_z=0.1, noisy=True, seed=0, z_shift=0.0):
        from sensor_msgs.msg import LaserScan, Range
        self.be, self.ual, self.shift, self.laser_z, self.z_shift = be, ual, shift, laser_z, z_shift
        self.noisy, self.blind, self.stop = noisy, False, False
        self.lag = 0.0
        self.boxes = None
        self.rng = np.random.default_rng(seed)
        self._msg, self._range = LaserScan, Range
        be.clock.start_thread(self._loop, name='laser scene')

    def ranges(self):
        z = float(self.ual.pos[2]) + self.laser_z - self.z_shift
        boxes = (wall_boxes(z, self.shift) if self.boxes is None else
                 self.boxes(z) if callable(self.boxes) else self.boxes)
        if self.noisy:
            return cast(self.ual.pos[:2], self.ual.yaw, boxes, 0.01, 0.01, 0.02, self.rng)
        return cast(self.ual.pos[:2], self.ual.yaw, boxes)

    def scan(self, t, ranges):
        """A LaserScan of ranges taken at sim time t."""
        import rospy
        m = self._msg(angle_min=ANGLE_MIN, angle_increment=INC, range_min=0.15, range_max=25.0, ranges=list(ranges))
        m.header.stamp = rospy.Time.from_sec(t)
        return m

    def _loop(self):
        pending = deque()                    # (due, scan) in the order taken
        while not self.stop:
            now = self.be.clock.now()
            if self.be.subs.get('scan') is not None:
                r = np.full(BEAMS, np.nan) if self.blind else self.ranges()
                lag = self.lag(now) if callable(self.lag) else self.lag
                if lag is not None:
                    pending.append((now + lag, self.scan(now, r)))
            while pending and pending[0][0] <= now + 1e-9:
                msg = pending.popleft()[1]
                cb = self.be.subs.get('scan')
                if cb is not None:
                    cb(msg)
            alt = self.be.subs.get('altimeter')
            if alt is not None:            # height above the ground (the test worlds' places have no roof below)
                alt(self._range(range=float(self.ual.pos[2]) - self.z_shift))
            self.be.clock.sleep(0.1)
