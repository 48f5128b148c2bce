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

# A forward fire is only placed when the mean front laser range is under this (metres): beyond it the
# 32x32 camera cannot see a fire reliably and the laser may be looking past the building.
MAX_LASER_RANGE_FIRE = 7.5

# Defaults of the original node's private parameters.
DEFAULT_UAV_ID = "1"
DEFAULT_CAMERA_CONFIG = "FORWARD"
DEFAULT_THERMAL_THRESHOLD = 37.0
DEFAULT_COVARIANCE_X = 1.5
DEFAULT_COVARIANCE_Y = 1.5
DEFAULT_COVARIANCE_Z = 0.5
DEFAULT_ANGLE_AMPLITUDE_DEG = 5.0
DEFAULT_NUM_FRAME_FILTER = 15
# Extensions of this port (0 / 0.0 give the original behaviour), see README.md:
# consecutive cold frames forgiven once a fire is confirmed (a dropped or occluded frame must not reset
# the 15-frame filter), and the temperature a pixel must reach to count as fire (a sun-heated facade at
# 40-45 degC passes the 37 degC threshold in every frame, so no frame count can reject it, and it merges
# with the fire into one contour; flames, heaters and plates read well above 50 degC up to 8 m).
DEFAULT_FALSE_NEGATIVE_TOLERANCE = 3
DEFAULT_MIN_FIRE_TEMPERATURE = 50.0

# Ground height (arena frame) at which DOWNWARD fires are placed.
GROUND_Z = 0.0
