"""Synthetic raw thermal frames (32 x 32 deg C, as teraranger_evo_thermal/raw_temp_array) of a fire on a wall.

The fire is a disk of `radius` px whose pixels stand `contrast` deg C above the wall (its rim half of it), the
wall at `wall` deg C with an optional left-to-right gradient (a sun-heated wall), a camera offset and Gaussian
pixel noise: the model is ours, not the simulator's (the agents must hold for any such numbers).
"""
import numpy as np
from std_msgs.msg import Float64MultiArray

TOPIC = 'teraranger_evo_thermal/raw_temp_array'
SIZE = 32


def fire_frame(contrast, wall=31.0, noise=0.5, rng=None, radius=8.0, centre=(15.5, 15.5), gradient=0.0,
               offset=0.0):
    """One frame: (32, 32) deg C."""
    rows, cols = np.mgrid[0:SIZE, 0:SIZE]
    r = np.hypot(rows - centre[0], cols - centre[1])
    level = np.where(r <= radius - 1.0, 1.0, np.where(r <= radius, 0.5, 0.0))
    frame = wall + offset + gradient * (cols / (SIZE - 1) - 0.5) + contrast * level
    if noise > 0.0:
        frame = frame + (rng or np.random.default_rng()).normal(0.0, noise, frame.shape)
    return frame


def message(frame):
    return Float64MultiArray(data=np.asarray(frame, dtype=np.float64).ravel())


def publish(backend, frame):
    """Hand a frame to the agent's subscriber (when it has one)."""
    cb = backend.subs.get(TOPIC)
    if cb is not None:
        cb(message(frame))


def ring_frame(contrast, centre, outer=20.0, hole=6.5, hole_share=0.4, wall=35.0, noise=0.5, rng=None):
    """A fire holder seen from near (32, 32): a ring of flames `contrast` deg C over the wall out to `outer` px
    from `centre` (row, column), wider than the frame when outer > 16, around a hole of `hole` px radius that
    reads hole_share of the ring's rise (a heater in it): the view of a holder from its watering distance."""
    rows, cols = np.mgrid[0:SIZE, 0:SIZE]
    r = np.hypot(rows - centre[0], cols - centre[1])
    level = np.where(r <= hole, hole_share, np.where(r <= outer, 1.0, 0.0))
    frame = wall + contrast * level
    if noise > 0.0:
        frame = frame + (rng or np.random.default_rng()).normal(0.0, noise, frame.shape)
    return frame
