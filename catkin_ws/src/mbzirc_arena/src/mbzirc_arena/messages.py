"""The constants of the messages the robots exchange, named once (no ROS import needed to use them).

Why here: pure cores (the estimator, the strategy, the tasks) decide on these values without importing the
generated message classes, and bare numbers (`ual_state in (4, 5)`, `color = 6`) say nothing to a reader.
`test_messages.py` checks every value against the `.msg` files, so they cannot drift apart.
"""
from __future__ import annotations

import math

# ---- mbzirc_comm_objs/ObjectDetection TYPE_* and COLOR_* ---------------------------------------------
TYPE_UNKNOWN = 0
TYPE_FIRE = 8
TYPE_HOLE = 9
COLOR_UNKNOWN = 0
COLOR_FIRE = 6

# ---- mbzirc_comm_objs/Object SUBTYPE_* and STATUS_* (SetObjectStatus uses the same status values) -----
SUBTYPE_UNKNOWN = 0
SUBTYPE_FACADE = 1
SUBTYPE_GROUND = 2
SUBTYPE_INDOOR = 3
STATUS_INACTIVE = 0
STATUS_ACTIVE = 1
STATUS_DETECTED = 2
STATUS_LOST = 3
STATUS_EXTINGUISHED = 4
STATUS_NAMES = {STATUS_INACTIVE: 'INACTIVE', STATUS_ACTIVE: 'ACTIVE', STATUS_DETECTED: 'DETECTED',
                STATUS_LOST: 'LOST', STATUS_EXTINGUISHED: 'EXTINGUISHED'}

# ---- mbzirc_comm_objs/ThermalImage camera_direction ---------------------------------------------------
CAMERA_DIRECTION_UNKNOWN = 0
CAMERA_DIRECTION_FORWARD = 1
CAMERA_DIRECTION_DOWNWARD = 2

# ---- uav_abstraction_layer/State ----------------------------------------------------------------------
UAL_UNINITIALIZED = 0
UAL_LANDED_DISARMED = 1
UAL_LANDED_ARMED = 2
UAL_TAKING_OFF = 3
UAL_FLYING_AUTO = 4
UAL_FLYING_MANUAL = 5
UAL_LANDING = 6
UAL_FLYING = (UAL_FLYING_AUTO, UAL_FLYING_MANUAL)          # in the air and taking set-points
UAL_LANDED = (UAL_UNINITIALIZED, UAL_LANDED_DISARMED, UAL_LANDED_ARMED)

# ---- mbzirc_comm_objs/AgentDataFeed robot_type and payload strings ------------------------------------
ROBOT_UAV = 'uav'
ROBOT_UGV = 'ugv'
PAYLOAD_WATER = 'water'
PAYLOAD_BLANKET = 'blanket'
# AgentDataFeed active_sub_state of an idle agent with no trusted pose (no GNSS fix, no valid indoor
# localization): '<this>: <why>'. The central unit sends it no goal meanwhile (each would fail at once, and
# would stop the robot backing out the way it came)
NO_TRUSTED_POSE = 'NO_TRUSTED_POSE'

# ---- names (docs/interfaces.md) -------------------------------------------------------------------------
GLOBAL_FRAME = 'arena'   # the frame of every pose the robots exchange
UGV_ID = '0'             # robot 0 is the UGV, 1..N the UAVs


def robot_ns(agent_id) -> str:
    """Namespace of a robot: the original team's naming, `mbzirc2020_<id>`."""
    return f'mbzirc2020_{agent_id}'


def feed_position(feed):
    """(x, y, z) of an AgentDataFeed's pose; None while the agent has none yet or it is not finite.

    Rule: a PoseStamped without a frame_id is no place. An agent publishes its feed before the UAL's first
    pose, with an empty PoseStamped whose (0, 0, 0) is not where the robot is.
    """
    if not feed.pose.header.frame_id:
        return None
    p = feed.pose.pose.position
    xyz = (p.x, p.y, p.z)
    return xyz if all(math.isfinite(v) for v in xyz) else None
