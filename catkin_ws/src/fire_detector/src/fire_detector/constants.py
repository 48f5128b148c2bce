"""Every constant of the fire detector in one place (sensor geometry, defaults of the original node)."""
import math

# TeraRanger Evo Thermal 33: 32 x 32 pixels, 33 degree field of view, row-major, row 0 = top.
IMG_WIDTH = 32
IMG_HEIGHT = 32
NUM_PIXELS = IMG_WIDTH * IMG_HEIGHT
FOV_DEG = 33.0
# Pinhole focal length in pixels; the optical centre is between the two middle pixels (OpenCV moments
# put pixel centres at integer coordinates, so the centre of a 32 px axis is 15.5).
FOCAL_PX = (IMG_WIDTH / 2.0) / math.tan(math.radians(FOV_DEG / 2.0))
CENTER_U = (IMG_WIDTH - 1) / 2.0
CENTER_V = (IMG_HEIGHT - 1) / 2.0

# Camera directions: mbzirc_comm_objs/ThermalImage.CAMERA_DIRECTION_*, named once in mbzirc_arena.
from mbzirc_arena.messages import (CAMERA_DIRECTION_DOWNWARD, CAMERA_DIRECTION_FORWARD,  # noqa: E402,F401
                                   CAMERA_DIRECTION_UNKNOWN)
CAMERA_CONFIGS = {"FORWARD": CAMERA_DIRECTION_FORWARD, "DOWNWARD": CAMERA_DIRECTION_DOWNWARD}

# The original's two laser gates (FORWARD; metres of mean front range): a hot frame counts towards the
# frame filter only under HOT_FRAME_MAX_RANGE, and a confirmed fire is answered by CheckFire and placed only
# under MAX_LASER_RANGE_FIRE (beyond it the 32x32 camera cannot see a fire reliably and the laser may be
# looking past the building). A front window without any valid beam passes both, as in the original
# (its mean of no valid beam was 0).
HOT_FRAME_MAX_RANGE = 5.0
MAX_LASER_RANGE_FIRE = 7.5
# The original's size of a detection in the image (its debug circle R_CIRCLE 70 px / SCALE_FACTOR 20).
ORIGINAL_SPOT_SIZE_PX = 3.5

# Defaults of the original node's private parameters.
DEFAULT_UAV_ID = "1"
DEFAULT_CAMERA_CONFIG = "FORWARD"
DEFAULT_THERMAL_THRESHOLD = 37.0
DEFAULT_COVARIANCE_X = 1.5
DEFAULT_COVARIANCE_Y = 1.5
DEFAULT_COVARIANCE_Z = 0.5
DEFAULT_ANGLE_AMPLITUDE_DEG = 5.0
DEFAULT_NUM_FRAME_FILTER = 15
# Beyond the original (README.md): consecutive cold frames forgiven once a fire is confirmed (a dropped or
# occluded frame must not reset the 15-frame filter); and what makes a hot pixel a flame rather than a
# sun-heated wall, which passes the 37 degC threshold in every frame (desert facades read 35-55 degC, so
# no frame count and no fixed floor below 55 degC can reject them): its contrast to the frame's median
# (the surface the camera looks at), or a temperature no sun-heated surface reaches; and a hot band that
# crosses the whole frame while filling little of it is the warm edge of a surface against the sky.
DEFAULT_FALSE_NEGATIVE_TOLERANCE = 3
DEFAULT_MIN_CONTRAST = 30.0            # degC above the frame's median
DEFAULT_SATURATION_TEMPERATURE = 100.0  # degC: hotter than any sun-heated building surface (they reach ~70)
DEFAULT_BAND_MAX_FILL = 0.5            # a frame-crossing hot region filling less than this is an edge

# Ground height (arena frame) at which DOWNWARD fires are placed.
GROUND_Z = 0.0
