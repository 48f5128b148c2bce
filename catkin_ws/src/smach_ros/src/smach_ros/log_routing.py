"""Routes smach's logging and shutdown check to rospy (done once when smach_ros is imported)."""
import rospy

import smach


def route_smach_to_rospy() -> None:
    smach.set_loggers(rospy.loginfo, rospy.logwarn, rospy.logdebug, rospy.logerr)
    smach.set_shutdown_check(rospy.is_shutdown)
