"""Every constant of the central unit in one place: task names, fire kinds, strategy defaults.

The arena (building, floors, holders) and the message constants are mbzirc_arena's, re-exported here for the
strategy; nothing here comes from the simulator's ground truth.
"""
from __future__ import annotations

from mbzirc_arena import c3 as _arena
from mbzirc_arena.messages import (  # noqa: F401  (re-exported for the strategy and the node)
    NO_TRUSTED_POSE, PAYLOAD_BLANKET, PAYLOAD_WATER, ROBOT_UAV, ROBOT_UGV, STATUS_ACTIVE, STATUS_DETECTED, STATUS_EXTINGUISHED,
    STATUS_INACTIVE, STATUS_LOST, SUBTYPE_FACADE, SUBTYPE_GROUND, SUBTYPE_INDOOR, SUBTYPE_UNKNOWN, TYPE_FIRE,
    UAL_FLYING_AUTO, UAL_FLYING_MANUAL, UAL_LANDED, UAL_LANDED_ARMED, UAL_LANDED_DISARMED, UAL_LANDING,
    UAL_TAKING_OFF, UAL_UNINITIALIZED, UGV_ID, robot_ns)

TOWER_BOX = _arena.TOWER_BOX   # (x_min, y_min, z_min, x_max, y_max, z_max)


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
MISSION_DURATION = _arena.TRIAL_DURATION   # s, 20 minutes
MAX_TASK_FAILURES = 3           # failures of one task kind on one target before giving it up
# failure_rules.py: a leg the agent's laser saw blocked is not sent again before a back-off doubling from
# LEG_BLOCKED_BACKOFF s up to LEG_BLOCKED_BACKOFF_MAX s; MAX_BLOCKED_LEGS blocked failures: target given up
LEG_BLOCKED_BACKOFF = 10.0
LEG_BLOCKED_BACKOFF_MAX = 60.0
MAX_BLOCKED_LEGS = 3
# 'not seen hot' aborts (after water from its watering pose, any robots) before a fire is doubted (failure_rules.py)
NOT_SEEN_HOT_LIMIT = 2
# the same for a facade fire watered hot before (its hole locked and watered; failure_rules.py)
FACADE_TOP_UP_LIMIT = 1
# Transit altitude per UAV id: each UAV flies outside the building at its own altitude. 4 m apart: the agents'
# boxes reach 1.5 m above and below a UAV (hold box 1 m + 0.5 m for the error of its reported height,
# mbzirc_agents pose_error_boxes.py), and 0.5 m more on each UAV for the height it holds: a take-off goes its
# height above the pad's reported height, off by the vertical GNSS bias (realistic seed 108: 3.5 m apart, UAV 1
# held 4.5 and UAV 2 7.3 over their pads, their hold boxes overlapped, each one's go_to waited for the other's
# hold for 360 s). UAVs crossing at their own altitudes, or hovering over neighbouring pads, need not wait for
# each other. The highest (12 m, its box to 14 m) stays under the 20 m ceiling and goes around the tower.
DEFAULT_ALTITUDES = {"1": 4.0, "2": 8.0, "3": 12.0}
ALTITUDE_BASE = 4.0
ALTITUDE_STEP = 4.0
