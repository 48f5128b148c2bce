"""Names of the wire constants the page shows, and the ages after which a source counts as stale.

The project's message values come from `mbzirc_arena.messages` (checked there against the .msg files);
actionlib_msgs/GoalStatus's are copied here so that the core needs no ROS import.
"""
from mbzirc_arena import messages as M

UAL_STATES = {M.UAL_UNINITIALIZED: "UNINITIALIZED", M.UAL_LANDED_DISARMED: "LANDED_DISARMED",
              M.UAL_LANDED_ARMED: "LANDED_ARMED", M.UAL_TAKING_OFF: "TAKING_OFF",
              M.UAL_FLYING_AUTO: "FLYING_AUTO", M.UAL_FLYING_MANUAL: "FLYING_MANUAL", M.UAL_LANDING: "LANDING"}
FIRE_STATUS = dict(M.STATUS_NAMES)
FIRE_KIND = {M.SUBTYPE_UNKNOWN: "unknown", M.SUBTYPE_FACADE: "facade", M.SUBTYPE_GROUND: "ground",
             M.SUBTYPE_INDOOR: "indoor"}
GOAL_STATUS = {0: "PENDING", 1: "ACTIVE", 2: "PREEMPTED", 3: "SUCCEEDED", 4: "ABORTED", 5: "REJECTED",
               6: "PREEMPTING", 7: "RECALLING", 8: "RECALLED", 9: "LOST"}

# Sim seconds after which a source is stale (each is published at least twice as often).
STALE_AFTER = {"data_feed": 2.0, "fires": 10.0, "cu_status": 3.0,
               "cu_heartbeat": 2.0, "score": 5.0, "regions": 5.0}
LINK_LATE_S = 1.0   # heartbeat (data_feed) older than this: "late"; older than STALE_AFTER: "stale"

ROBOT_NS = "/mbzirc2020_%s"
UGV_ID = M.UGV_ID
