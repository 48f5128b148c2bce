"""Every tunable number and default name of the robustness harness, in one place."""

# ---- fuzz generator ---------------------------------------------------------------------------------
DEFAULT_MAX_CASES = 40          # per topic / service: enough to hit every kind of bad input once
HUGE_STRING_LEN = 100_000       # characters of the "huge string" case
HUGE_BYTES = 1 << 20            # bytes of the "huge uint8[]" case (1 MiB, e.g. an image's data)
HUGE_ARRAY = 100_000            # elements of the "huge array" case
ODD_LENGTHS = (1, 1023, 1025)   # array lengths that break "exactly N values" assumptions (1024 thermal)
MANY_ELEMENTS = 200             # sub-messages in the "many elements" case
TEMPLATE_FRAME = "arena"        # header.frame_id of the template every mutation starts from
TEMPLATE_STRING = "1"           # other strings of the template (a plausible robot id)
SINGLE_FIELD_FLOATS = 8         # float fields that get a NaN / +inf of their own (the rest of the message valid)
MAX_DEPTH = 6                   # recursion limit when populating nested messages
HUGE_PICKLE_CHARS = 9 << 20     # base64 chars of the huge pickle (smach_ros refuses local_data over 8 MiB)
DEEP_PICKLE_LEVELS = 100_000    # nested lists of the deep pickle
PICKLE_MARKER_PREFIX = "mbzirc_fuzz_pickle_code_ran_"  # file the code-running pickles would create

# ---- fuzz runner ------------------------------------------------------------------------------------
DEFAULT_RATE_HZ = 20.0          # malformed messages per second per topic (keeps CPU modest)
CONNECT_TIMEOUT_S = 3.0         # wait for subscribers to connect to the fuzz publisher
SERVICE_CALL_TIMEOUT_S = 3.0    # a service that does not answer within this is reported as hung
MAX_SERVICE_TIMEOUTS = 2        # stop fuzzing a service after this many unanswered calls
CHECK_EVERY = 4                 # liveness (getPid) after every 4th case: a death names the last 4 cases
SETTLE_S = 0.3                  # after each topic: let the callbacks run before checking liveness
STRUCTURE_TIMEOUT_S = 6.0       # wait for an introspection server's container_structure (sent every 2 s)
XMLRPC_TIMEOUT_S = 3.0          # getPid on a node
DEFAULT_EXCLUDE_TOPICS = ("/clock", "/rosout", "/rosout_agg")
DEFAULT_EXCLUDE_SERVICES = ("*/get_loggers", "*/set_logger_level")
DEFAULT_EXCLUDE_NODES = ("/rosout",)
FLOOD_COUNT = 500               # valid messages sent at once to each topic (stress)
GOAL_STORM = 50                 # valid goals with distinct ids sent at once to each action goal topic
PREEMPT_RACES = 5               # goal + its cancel sent back to back
DISCOVERY_PASSES = 2            # nodes subscribe lazily (e.g. a tf listener made on first use): look again
ERROR_LEVELS = (8, 16)          # rosgraph_msgs/Log ERROR, FATAL
WARN_LEVEL = 4
# error lines rospy itself logs under the node's name: they do not show that the node checks its input
FRAMEWORK_ERRORS = ("Characters replaced when decoding message", "Unable to deserialize",
                    "Attempt to get a goal id on an uninitialized",  # actionlib's own checks
                    "Got a transition callback on a goal handle", "The goal handle is not tracking")

# ---- network-namespace harness ---------------------------------------------------------------------
NETNS_PREFIX = "mbzr"           # namespaces are named <prefix>-<owner pid>-<host>
SUBNET = "10.77"                # hosts get 10.77.<lab>.<n>/24, lab from the owner pid
GROUND_STATION = "gs"
MASTER_PORT = 11311

# ---- fault scenarios --------------------------------------------------------------------------------
LINK_CUT_S = 60.0               # the issue: cut one UAV's link for 60 s mid-mission
REPORT_DIR = "results/robustness"
