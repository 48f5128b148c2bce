"""Every constant of the central unit in one place: task names, building layout, floors, defaults.

The layout is the public Challenge 3 arena (c3_world.md): teams know the building and the fire holders in
advance; which holders burn is what they must find. Nothing here comes from the simulator's ground truth.
"""
from __future__ import annotations

# ---- robots ----------------------------------------------------------------------------------------
UGV_ID = "0"
PAYLOAD_WATER = "water"
PAYLOAD_BLANKET = "blanket"
ROBOT_UAV = "uav"
ROBOT_UGV = "ugv"


def robot_ns(agent_id: str) -> str:
    """Namespace of a robot (interfaces.md: `mbzirc2020_<id>`)."""
    return f"mbzirc2020_{agent_id}"


# ---- tasks (names of the agents' actions, `/mbzirc2020_<id>/<task>_action`) -------------------------
TAKE_OFF = "take_off"
LAND = "land"
GO_TO = "go_to"
FOLLOW_PATH = "follow_path"
HOVER = "hover"
SEARCH_FACADE = "search_facade"
GO_TO_FACADE_FIRE = "go_to_facade_fire"
EXTINGUISH_FACADE_FIRE = "extinguish_facade_fire"
LOOK_FOR_GROUND_FIRES = "look_for_ground_fires"
EXTINGUISH_GROUND_FIRE = "extinguish_ground_fire"
ENTER_BUILDING = "enter_building"
SEARCH_INDOOR = "search_indoor"
EXTINGUISH_INDOOR_FIRE = "extinguish_indoor_fire"
GO_HOME_AND_REFILL = "go_home_and_refill"

UAV_TASKS = (TAKE_OFF, LAND, GO_TO, FOLLOW_PATH, HOVER, SEARCH_FACADE, GO_TO_FACADE_FIRE,
             EXTINGUISH_FACADE_FIRE, LOOK_FOR_GROUND_FIRES, EXTINGUISH_GROUND_FIRE, ENTER_BUILDING,
             SEARCH_INDOOR, EXTINGUISH_INDOOR_FIRE, GO_HOME_AND_REFILL)
UGV_TASKS = (GO_TO, SEARCH_INDOOR, EXTINGUISH_INDOOR_FIRE)

# Tasks during which a UAV is at a facade floor (used to rebuild floor ownership after a restart).
FACADE_TASKS = (SEARCH_FACADE, GO_TO_FACADE_FIRE, EXTINGUISH_FACADE_FIRE)

# ---- fire kinds ------------------------------------------------------------------------------------
KIND_GROUND = "ground"
KIND_FACADE = "facade"
KIND_INDOOR = "indoor"
KIND_UNKNOWN = "unknown"

# Object (estimator) constants, mirrored so the pure core needs no ROS import.
TYPE_FIRE = 8
SUBTYPE_UNKNOWN, SUBTYPE_FACADE, SUBTYPE_GROUND, SUBTYPE_INDOOR = 0, 1, 2, 3
STATUS_INACTIVE, STATUS_ACTIVE, STATUS_DETECTED, STATUS_LOST, STATUS_EXTINGUISHED = 0, 1, 2, 3, 4

# uav_abstraction_layer/State values.
UAL_UNINITIALIZED, UAL_LANDED_DISARMED, UAL_LANDED_ARMED = 0, 1, 2
UAL_TAKING_OFF, UAL_FLYING_AUTO, UAL_FLYING_MANUAL, UAL_LANDING = 3, 4, 5, 6
UAL_LANDED = (UAL_UNINITIALIZED, UAL_LANDED_DISARMED, UAL_LANDED_ARMED)

# ---- building (arena frame, metres) -----------------------------------------------------------------
# Boxes as (xmin, ymin, zmin, xmax, ymax, zmax). The roof structure makes the tower 18 m high.
TOWER_BOX = (11.4, 6.7, 0.0, 24.2, 19.5, 18.0)
EXTENSION_BOX = (24.2, 6.7, 0.0, 37.0, 19.5, 4.5)
BUILDING_BOXES = (TOWER_BOX, EXTENSION_BOX)
# Floor f spans [FLOOR_BOUNDS[f], FLOOR_BOUNDS[f + 1]) in z.
FLOOR_BOUNDS = (-1.0, 5.0, 10.0, 30.0)
NUM_FLOORS = 3

# Facade fire holders of the default layout (c3_world.md).
FACADE_HOLDERS = (
    (12.4, 19.5, 6.5), (12.4, 19.5, 12.75), (17.4, 19.5, 10.5), (22.7, 19.5, 12.75), (23.7, 19.5, 0.75),
    (11.4, 8.5, 6.0), (11.4, 18.5, 2.75), (11.4, 18.5, 10.25), (11.4, 14.5, 10.5), (11.4, 8.5, 12.5),
    (24.2, 17.75, 6.0), (24.2, 12.7, 10.5), (24.2, 8.2, 12.5), (24.2, 18.8, 12.5), (24.2, 8.2, 8.25),
)
GROUND_FIRE_CANDIDATES = ((-9.0, 20.0, 0.0), (1.0, 14.0, 0.0))
# Open area where a second ground search sweeps (xmin, ymin, xmax, ymax) and its sweep spacing.
GROUND_SEARCH_AREA = (-14.0, 6.0, 6.5, 29.0)  # keeps clear of the home (take-off) area

# ---- strategy defaults (each is also a ~param of the node) ------------------------------------------
AGENT_TIMEOUT = 5.0             # s of data_feed silence before an agent's work is reassigned
FLOOR_PRIORITY = (2, 0, 1)      # the first floor (1) last: wind gusts
INDOOR_FLOORS = (1, 2)          # floors the UAVs search indoors (floor 0 is the UGV's)
FACADE_STANDOFF = 2.5           # m from the wall when searching a facade (thermal reliable 2-4 m)
ROUTE_MARGIN = 2.5              # m kept from the building when routing around it
ELEVATOR_MARGIN = 6.0           # m from the tower corners to the virtual elevators
# The virtual elevators (x, y): north-west of the tower (4.5 m from the outdoor holder at (5, 25)) and
# south-east of the extension's south wall.
ELEVATORS = ((9.0, 27.0), (30.2, 0.7))
FIRE_DISTANCE = 2.0             # m from the hole for go_to_facade_fire (jet range 3 m; more room to the wall)
MIN_WATER = 0.8                 # litres: below this a water UAV refills first (a fire takes about 1 L)
GROUND_SEARCH_ALTITUDE = 4.0  # downward thermal footprint about 2.4 m wide
GROUND_SWEEP_SPACING = 2.5
MISSION_DURATION = 1200.0       # s, 20 minutes
MAX_TASK_FAILURES = 3           # failures of one task kind on one target before giving it up
# Transit altitude per UAV id: each UAV flies outside the building at its own altitude.
DEFAULT_ALTITUDES = {"1": 4.0, "2": 6.0, "3": 8.0}
ALTITUDE_BASE = 4.0
ALTITUDE_STEP = 2.0
