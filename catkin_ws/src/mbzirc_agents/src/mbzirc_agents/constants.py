"""Constants of the agents, in one place (outcomes, names, world defaults).

Why one module: task outcomes, state names and the default world layout are shared by the framework,
the tasks, the nodes and the tests; string literals spread around drift apart.
"""
from __future__ import annotations

# ---- task outcomes (every task maps its outcomes to these) ------------------------------------------
SUCCESS = 'success'
ERROR = 'error'
PREEMPTED = 'preempted'
TASK_OUTCOMES = [SUCCESS, ERROR, PREEMPTED]

# ---- AgentStateMachine ------------------------------------------------------------------------------
DEFAULT_STATE = 'DEFAULT'
SM_END = 'end'              # the machine's only outcome: the node is shutting down
SHUTDOWN_OUTCOME = 'shutdown'

# ---- status of estimated objects (mbzirc_comm_objs/Object STATUS_*, same values as SetObjectStatus) --
STATUS_INACTIVE = 0
STATUS_ACTIVE = 1
STATUS_DETECTED = 2
STATUS_LOST = 3
STATUS_EXTINGUISHED = 4
STATUS_NAMES = {STATUS_INACTIVE: 'INACTIVE', STATUS_ACTIVE: 'ACTIVE', STATUS_DETECTED: 'DETECTED',
                STATUS_LOST: 'LOST', STATUS_EXTINGUISHED: 'EXTINGUISHED'}

# ObjectDetection TYPE_* and Object SUBTYPE_* we use.
TYPE_FIRE = 8
TYPE_HOLE = 9
SUBTYPE_UNKNOWN = 0
SUBTYPE_FACADE = 1
SUBTYPE_GROUND = 2
SUBTYPE_INDOOR = 3

# ThermalImage camera_direction
CAMERA_FORWARD = 1
CAMERA_DOWNWARD = 2

# ---- uav_abstraction_layer/State --------------------------------------------------------------------
UAL_UNINITIALIZED = 0
UAL_LANDED_DISARMED = 1
UAL_LANDED_ARMED = 2
UAL_TAKING_OFF = 3
UAL_FLYING_AUTO = 4
UAL_FLYING_MANUAL = 5
UAL_LANDING = 6

# ---- world (c3_world.md); every one of these is also a ~param of the nodes that use it ---------------
GLOBAL_FRAME = 'arena'
# Arena box (x_min, y_min, z_min, x_max, y_max, z_max): 60 m x 50 m x 20 m (ual_sim c3_default world).
ARENA_BOX = (-17.0, -13.0, 0.0, 43.0, 37.0, 20.0)
# Building footprints (x_min, y_min, x_max, y_max, height).
TOWER = (11.4, 6.7, 24.2, 19.5, 18.0)
EXTENSION = (24.2, 6.7, 37.0, 19.5, 4.5)
BUILDINGS = [TOWER, EXTENSION]
# Floors: z range of each floor (0 ground, 1 first, 2 second); a fire's floor is the range holding its z.
FLOOR_Z = [(0.0, 5.0), (5.0, 10.0), (10.0, 15.0)]
FACADE_HOLDERS = [
    (12.4, 19.5, 6.5), (12.4, 19.5, 12.75), (17.4, 19.5, 10.5), (22.7, 19.5, 12.75), (23.7, 19.5, 0.75),
    (11.4, 8.5, 6.0), (11.4, 18.5, 2.75), (11.4, 18.5, 10.25), (11.4, 14.5, 10.5), (11.4, 8.5, 12.5),
    (24.2, 17.75, 6.0), (24.2, 12.7, 10.5), (24.2, 8.2, 12.5), (24.2, 18.8, 12.5), (24.2, 8.2, 8.25),
]
OUTDOOR_FIRE_HOLDERS = [(-9.0, 20.0, 0.0), (1.0, 14.0, 0.0)]
# Default outdoor area searched for ground fires (x_min, y_min, x_max, y_max): around the holders.
GROUND_SEARCH_AREA = (-12.0, 6.0, 7.0, 30.0)
# UGV: the ground-floor door (facade B, x 13-15.5 at y = 6.7), a pose outside it and a search path inside.
UGV_DOOR_OUTSIDE = (14.25, 4.0)
UGV_DOOR_INSIDE = (14.25, 9.0)
# Viewpoints (x, y, yaw) ~5 m from the ground-floor indoor holders (17.7, 8.5) and (17.9, 16.5): the UGV's
# level thermal camera (at ground height in ual_sim) only sees a fire 1.5 m up from about 5 m away.
UGV_INDOOR_PATH = [(12.4, 8.5, 0.0), (16.5, 11.0, 0.0), (19.5, 11.0, 0.0), (23.0, 16.5, 3.14159)]

# ---- agent defaults ---------------------------------------------------------------------------------
CONTROL_RATE_HZ = 10.0          # every control / monitoring loop of a task
DATA_FEED_RATE_HZ = 10.0
HEARTBEAT_TOPIC = '/central_unit/heartbeat'
CENTRAL_UNIT_TIMEOUT = 5.0
RETURN_HOME_TIMEOUT = 60.0
REGION_MARGIN = 1.0             # m added around every reserved box
REGION_WAIT_TIMEOUT = 60.0      # s a go-to waits for its region before giving up
HOLD_HALF_SIZE = 1.0            # half side of the box held around a hovering UAV
POSITION_TOLERANCE = 0.2        # m, a go-to has arrived (the UAL stops within 0.1 m)
YAW_TOLERANCE = 0.15            # rad
FACADE_STANDOFF = 2.0           # m in front of a facade fire holder

# extinguish_facade_fire safety (why: estimates that jump or drift flew UAVs into the wall)
POSE_HISTORY_LEN = 200          # poses kept for pose_at (several seconds at the UAL's 30-50 Hz)
HOLE_JUMP_MAX = 1.5             # m: a hole position further than this from the locked one -> abort
HOLE_SAME_MAX = 0.35            # m: a circle this close to the locked hole is that hole (decoys: 0.7 m aside)
COLD_CHECKS = 6                 # consecutive "no fire" CheckFire answers (0.5 s apart) -> fire is out; the
#                                 water keeps flowing meanwhile: a nearly quenched heater reads cold while its
#                                 container still misses some 8 % (seen: fires left at 92-96 % after 3 checks)
FIRE_LITRES = 1.0               # L into a facade / indoor fire's container to put it out (c3_world.md): a run
#                                 whose tank ran dry calls a cold fire out only after delivering this much
INDOOR_HIT_SHARE = 0.6          # share of the jet credited as in while aiming at an indoor fire's estimate (no
#                                 hole detector there): seen ~0.75 in missions; a dry-tank run then calls a cold
#                                 fire out only after >= 1.67 L pumped (seen: 1.2 L left a fire at 92 %)
HOLE_RADIUS = 0.15              # m: a facade fire's hole (the container's mouth)
JET_SPOT_RADIUS = 0.11          # m: radius of the water spot at the shooting distance (nozzle calibration)
SCAN_MAX_AGE = 0.5              # s: an older laser scan does not clamp (keep_off_walls still does)
HOLE_DEMAND_TOPIC = 'circle_detection/middle_hole'   # subscribed while a task needs holes (lazy detector)
