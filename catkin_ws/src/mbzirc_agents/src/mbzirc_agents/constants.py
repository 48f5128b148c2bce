"""Constants of the agents, in one place (outcomes, names, defaults).

Why one module: task outcomes, state names and defaults are shared by the framework, the tasks, the nodes
and the tests; string literals spread around drift apart. The arena and the message constants come from
mbzirc_arena (re-exported below), never copied here.
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

# ---- messages and the arena: named once in mbzirc_arena, re-exported for the tasks ----------------------
from mbzirc_arena import c3 as _arena  # noqa: E402
from mbzirc_arena.messages import (  # noqa: E402,F401
    CAMERA_DIRECTION_DOWNWARD as CAMERA_DOWNWARD, CAMERA_DIRECTION_FORWARD as CAMERA_FORWARD, GLOBAL_FRAME,
    NO_TRUSTED_POSE,
    STATUS_ACTIVE, STATUS_DETECTED, STATUS_EXTINGUISHED, STATUS_INACTIVE, STATUS_LOST, STATUS_NAMES,
    SUBTYPE_FACADE, SUBTYPE_GROUND, SUBTYPE_INDOOR, SUBTYPE_UNKNOWN, TYPE_FIRE, TYPE_HOLE, UAL_FLYING,
    UAL_FLYING_AUTO, UAL_FLYING_MANUAL, UAL_LANDED_ARMED, UAL_LANDED_DISARMED, UAL_LANDING, UAL_TAKING_OFF,
    UAL_UNINITIALIZED)

ARENA_BOX = _arena.BOUNDS             # (x_min, y_min, z_min, x_max, y_max, z_max)
TOWER = _arena.TOWER                  # footprints (x_min, y_min, x_max, y_max, top)
EXTENSION = _arena.EXTENSION
BUILDINGS = list(_arena.FOOTPRINTS)
FACADE_HOLDERS = list(_arena.FACADE_HOLDERS)
FLOOR_HEIGHTS = tuple(_arena.FLOOR_HEIGHTS)

# ---- agent defaults of the default arena (each is also a ~param of the nodes that use it) ------------------
# Default outdoor area searched for ground fires (x_min, y_min, x_max, y_max): around the ground fire places.
GROUND_SEARCH_AREA = (-12.0, 6.0, 7.0, 30.0)
# UGV: a pose outside the ground-floor door of facade B and one inside it (the door's centre +- along its
# normal), and a search path inside.
_DOOR_B = next(d for d in _arena.ARENA.doors('tower') if d.wall == 'facade_B')
UGV_DOOR_OUTSIDE = (_DOOR_B.centre[0] + 2.7 * _DOOR_B.normal[0], _DOOR_B.centre[1] + 2.7 * _DOOR_B.normal[1])
UGV_DOOR_INSIDE = (_DOOR_B.centre[0] - 2.3 * _DOOR_B.normal[0], _DOOR_B.centre[1] - 2.3 * _DOOR_B.normal[1])
# Viewpoints (x, y, yaw) ~5 m from where the ground-floor indoor fires were in the simulated world: private
# knowledge (docs/arena_knowledge.md), to be replaced by exploration (issue 18). The UGV's level thermal
# camera only sees a fire 1.5 m up from about 5 m away.
# The first and the last stand 1.8 m off facade C's and D's inner faces (they stood 0.8 and 1.0 m off: with
# the UGV's 0.6 m radius and a metre of GNSS error it hit the wall under realistic uncertainty, seeds 101, 102).
UGV_INDOOR_PATH = [(13.4, 8.5, 0.0), (16.5, 11.0, 0.0), (19.5, 11.0, 0.0), (22.2, 16.5, 3.14159)]

# ---- agent defaults ---------------------------------------------------------------------------------
CONTROL_RATE_HZ = 10.0          # every control / monitoring loop of a task
DATA_FEED_RATE_HZ = 10.0
DATA_FEED_IDLE_PERIOD = 0.5      # s between two data_feeds that say the same (the ground station: 'late' after 1 s)
HEARTBEAT_TOPIC = '/central_unit/heartbeat'
CENTRAL_UNIT_TIMEOUT = 5.0
RETURN_HOME_TIMEOUT = 60.0
REGION_MARGIN = 1.0             # m added around every reserved box
REGION_WAIT_TIMEOUT = 60.0      # s a go-to waits for its region before giving up
HOLD_HALF_SIZE = 1.0            # half side of the box held around a hovering UAV
# m per axis a team allows for the error of one robot's reported pose (pose_error_boxes.py): standard
# single-frequency GNSS (the trial penalised RTK) is off by about a metre horizontally (some 0.7 m per axis,
# 1 sigma, wandering slowly); vertically the UAL's height (GNSS fused with a barometer) by about half a metre
# between two robots nearby. The central unit's transit altitudes are 2 x (HOLD_HALF_SIZE + POSE_ERROR_MARGIN_Z)
# + 2 x 0.5 m (the heights two UAVs hold) apart, so that UAVs crossing at their own altitudes do not wait for each other. A team on RTK: a few cm
POSE_ERROR_MARGIN = 0.75
POSE_ERROR_MARGIN_Z = 0.5
POSITION_TOLERANCE = 0.2        # m, a go-to has arrived (the UAL stops within 0.1 m)
YAW_TOLERANCE = 0.15            # rad
FACADE_STANDOFF = 2.0           # m in front of a facade fire holder

# extinguish_facade_fire safety (why: estimates that jump or drift flew UAVs into the wall)
POSE_HISTORY_LEN = 200          # poses kept for pose_at (several seconds at the UAL's 30-50 Hz)
HOLE_JUMP_MAX = 1.5             # m: a hole position further than this from the locked one -> abort
HOLE_SAME_MAX = 0.35            # m: a circle this close to the locked hole is that hole (decoys: 0.7 m aside)
COLD_CHECKS = 6                 # consecutive cold answers (0.5 s apart) -> fire is out. Facade: the jet stays
#                                 on the hole meanwhile (a nearly quenched heater reads cold while its container
#                                 still misses some 8 %: fires left at 92-96 % after 3 checks). Indoors the soak
#                                 gives that margin and the pump is off while they are counted (tasks/indoor.py)
# keeping off the walls with no trusted pose (robot_agent._keep_off_walls_without_pose): a slow, damped move
BLIND_BACK_OFF_GAIN = 1.0       # 1/s: velocity per metre still to go
BLIND_BACK_OFF_SPEED = 0.3      # m/s at most
SCAN_MAX_AGE = 0.5              # s: an older laser scan does not clamp (keep_off_walls still does)
HOLE_DEMAND_TOPIC = 'circle_detection/middle_hole'   # subscribed while a task needs holes (lazy detector)

# the agent's state machine is restarted this many times when an exception escapes it, then the agent is failed
SM_MAX_RESTARTS = 3
# a first pose above this (m) is in the air: a respawned agent, whose home and regions are not here
ON_GROUND_MAX_Z = 0.5
# m: a landed robot reported this close to its home pad stands on it (a few sigma of the GNSS error; pads are
# 3.3 m apart): its boxes go on the pad, and landing farther than this is landing away from home
HOME_PAD_RADIUS = 1.5
# wall seconds without a sign of life from the state machine (idle loop, task checks, feedback) before the
# agent withholds its data_feed: its work is then the central unit's to give to others
SM_STALL_S = 30.0
