"""Names of the wire constants the page shows, and the ages after which a source counts as stale.

The numbers are those of the message definitions (uav_abstraction_layer/State, mbzirc_comm_objs/Object,
actionlib_msgs/GoalStatus); they are copied here so that the core needs no ROS import.
"""
UAL_STATES = {0: "UNINITIALIZED", 1: "LANDED_DISARMED", 2: "LANDED_ARMED", 3: "TAKING_OFF", 4: "FLYING_AUTO",
              5: "FLYING_MANUAL", 6: "LANDING"}
FIRE_STATUS = {0: "INACTIVE", 1: "ACTIVE", 2: "DETECTED", 3: "LOST", 4: "EXTINGUISHED"}
FIRE_KIND = {0: "unknown", 1: "facade", 2: "ground", 3: "indoor"}
GOAL_STATUS = {0: "PENDING", 1: "ACTIVE", 2: "PREEMPTED", 3: "SUCCEEDED", 4: "ABORTED", 5: "REJECTED",
               6: "PREEMPTING", 7: "RECALLING", 8: "RECALLED", 9: "LOST"}

# Sim seconds after which a source is stale (each is published at least twice as often).
STALE_AFTER = {"data_feed": 2.0, "fires": 10.0, "cu_status": 3.0,
               "cu_heartbeat": 2.0, "score": 5.0, "regions": 5.0}
LINK_LATE_S = 1.0   # heartbeat (data_feed) older than this: "late"; older than STALE_AFTER: "stale"

ROBOT_NS = "/mbzirc2020_%s"
UGV_ID = "0"
