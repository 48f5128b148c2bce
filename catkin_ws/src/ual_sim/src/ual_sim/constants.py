"""Every tunable default of the simulator in one place (documented in docs/interfaces.md, ual_sim section).

Why here: the agents are tuned against these numbers (tank size, flow, jet range, refill rule), so they
must not be scattered through the code.
"""
import math

# --- UAL states (uav_abstraction_layer/State, named once in mbzirc_arena: the core stays free of ROS) ---
from mbzirc_arena import messages as _M  # noqa: E402
from mbzirc_arena.messages import (UAL_FLYING_AUTO as FLYING_AUTO, UAL_FLYING_MANUAL as FLYING_MANUAL,  # noqa: E402
                                   UAL_LANDED_ARMED as LANDED_ARMED, UAL_LANDED_DISARMED as LANDED_DISARMED,
                                   UAL_LANDING as LANDING, UAL_TAKING_OFF as TAKING_OFF,
                                   UAL_UNINITIALIZED as UNINITIALIZED)
FLYING_STATES = (TAKING_OFF, FLYING_AUTO, FLYING_MANUAL, LANDING)

# --- kinematics (defaults of the original UAL light simulation) ---
UAV_MAX_VXY = 1.6          # m/s
UAV_MAX_VZ = 1.2           # m/s
UAV_MAX_YAW_RATE = 1.0     # rad/s
UGV_MAX_V = 1.0            # m/s
UGV_MAX_YAW_RATE = 1.0     # rad/s
GOAL_TOL_YAW = 0.05        # rad: heading tolerance of a reached go_to (the position is reached exactly)
VELOCITY_CMD_TIMEOUT = 0.5  # s: a set_velocity older than this stops the robot (hover)
LANDED_Z_TOL = 0.02        # m above the support surface that counts as touched down

# --- collision bodies (spheres around base_link + offset) ---
UAV_RADIUS = 0.35          # m (a 0.8 m frame, props included, fits through a 2 m window)
UAV_BODY_OFFSET_Z = 0.15   # m
UGV_RADIUS = 0.6           # m (must fit through a 2.5 m door)
UGV_BODY_OFFSET_Z = 0.5    # m
UGV_HEIGHT = 1.0           # m
INDOOR_HOLE_Z = 1.5        # m: indoor fire holes sit this high above their floor (worlds/c3_default.yaml)
# The UGV's mast: its FORWARD thermal camera, RGB-D camera and nozzle sit at the indoor hole height, so that
# parked 1.5-2.5 m in front of an indoor fire, facing it, the hot ring is near the thermal image centre and
# the level jet enters the hole (a camera at 0.8 m saw it only in its top rows, off-centre).
UGV_MAST_Z = INDOOR_HOLE_Z  # m above base_link: thermal_link and camera_color_optical_frame
UGV_NOZZLE_Z = UGV_MAST_Z  # m above base_link: the nozzle on the same mast
UGV_LASER_Z = 0.8          # m above base_link: the 2D laser stays low on the chassis (below the 1.5 m sills)

# --- water and blanket ---
TANK_LITRES = 2.0          # L per refill
PUMP_FLOW = 0.2            # L/s
LITRES_PER_FIRE = 1.0      # L into the container to put a facade/indoor fire out
JET_RANGE = 3.0            # m: water beyond this falls short
JET_SPREAD_R0 = 0.05       # m: radius of the water spot at the nozzle
JET_SPREAD_PER_M = 0.04    # m of spot radius per metre of flight
NOZZLE_OFFSET = (0.3, 0.0, 0.0)  # base_link
HOLE_RADIUS = 0.15         # m: hole of a facade/indoor fire (its container is behind)
FLAME_RING_RADIUS = 0.4    # m: outer radius of the ring of flames around the hole
DECOY_OFFSET = 0.7         # m: the two decoy circles left and right of the hole
DECOY_RADIUS = 0.15        # m
GROUND_PLATE_RADIUS = 0.5  # m: heated plate under red silk
BLANKET_MAX_OFFSET = 0.6   # m: blanket centre within this of the plate centre covers it
BLANKET_MAX_HEIGHT = 4.0   # m: released higher than this, the blanket drifts off and does not count
BLANKET_SIZE = 1.5         # m side (markers)
REFILL_RADIUS = 1.5        # m from home
REFILL_TIME = 5.0          # s landed and disarmed near home -> tank full, new blanket

# --- temperature model (deg C) ---
AMBIENT_TEMP = 30.0
SKY_TEMP = 20.0
GROUND_TEMP = 34.0
INDOOR_WALL_TEMP = 31.0
FLAME_TEMP = 250.0         # ring of gas flames
HEATER_TEMP = 120.0        # resistor in the hole centre / ground plates
BLANKET_TEMP = 45.0        # a plate under the blanket
INACTIVE_HOLDER_TEMP = 28.0
THERMAL_NOISE_STD = 0.5
THERMAL_ATTEN_DIST = 6.0   # m: apparent contrast = 1 / (1 + (d / this)^2)
THERMAL_MAX_RANGE = 15.0   # m: beyond this a beam sees sky/ambient
THERMAL_FOV = math.radians(33.0)
THERMAL_SIZE = 32
THERMAL_RATE = 14.0        # Hz
THERMAL_PTAT = 32.0        # sensor's own temperature

# --- laser (RPLidar) ---
LASER_BEAMS = 720
LASER_RANGE_MIN = 0.15
LASER_RANGE_MAX = 25.0
LASER_RATE = 10.0          # Hz
LASER_OFFSET = (0.0, 0.0, 0.1)   # base_link -> laser_link

# --- downward altimeter (laser rangefinder, Garmin LIDAR-Lite v3HP class; sources: README "Altimeter") ---
ALTIMETER_RATE = 20.0          # Hz published (the sensor ranges at up to 1 kHz; a 10 Hz controller needs 20)
ALTIMETER_RANGE_MIN = 0.05     # m: below it the reading is -inf (landed)
ALTIMETER_RANGE_MAX = 40.0     # m: beyond it +inf (no return)
ALTIMETER_FOV = 0.008          # rad: beam divergence
ALTIMETER_NEAR_LIMIT = 2.0     # m: under it the datasheet's accuracy is the coarser one
ALTIMETER_NOISE_NEAR = 0.05    # m std under ALTIMETER_NEAR_LIMIT (not under `ideal`)
ALTIMETER_NOISE_FAR = 0.025    # m std from ALTIMETER_NEAR_LIMIT on (not under `ideal`)
ALTIMETER_DROPOUT_RATE = 0.01  # share of invalid (NaN) readings (not under `ideal`)

# --- RGB-D (RealSense D435i) ---
CAM_WIDTH = 640
CAM_HEIGHT = 480
CAM_FX = 462.1
CAM_FY = 462.1
CAM_CX = 320.0
CAM_CY = 240.0
CAM_RATE = 15.0            # Hz
CAM_DEPTH_MIN = 0.2        # m
CAM_DEPTH_MAX = 10.0       # m
CAM_OFFSET = (0.15, 0.0, 0.0)    # base_link -> camera_color_optical_frame (rotation: optical)
THERMAL_OFFSET_FORWARD = (0.2, 0.0, 0.0)
THERMAL_OFFSET_DOWNWARD = (0.0, 0.0, -0.1)

# --- rates and trial ---
PUB_RATE = 30.0            # Hz: pose, velocity, odom, TF
STATE_KEEPALIVE_S = 1.0    # s: ual/state is sent when it changes, and at least this often (sim time)
SIM_RATE = 30.0            # Hz: physics ticks
CLOCK_RATE = 100.0         # Hz of wall time at most for /clock (one per tick)
TRIAL_DURATION = 1200.0    # s
MARKER_RATE = 2.0          # Hz
FIRES_RATE = 2.0           # Hz (/sim/fires, /sim/score)

# --- wind gusts near the first floor ---
WIND_Z_RANGE = (4.0, 10.0)  # m
WIND_MAX_DIST = 4.0        # m from the tower footprint
WIND_GUST_STD = 0.6        # m/s: Ornstein-Uhlenbeck gust velocity (a position error of ~0.1-0.4 m after the controller)
WIND_GUST_TAU = 2.0        # s
HOLD_GAIN = 2.0            # 1/s: position-hold pull back to the set-point

# --- payload names ---
PAYLOAD_WATER = "water"
PAYLOAD_BLANKET = "blanket"
UGV_ID = int(_M.UGV_ID)
FRAME_ARENA = _M.GLOBAL_FRAME
robot_ns = _M.robot_ns   # `mbzirc2020_<id>`, the original team's naming
