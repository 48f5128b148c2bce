#!/usr/bin/env python3
"""Fixture: publishes std_msgs/Header on `tick` every 0.2 s of ROS time, from a PeriodicTimer, or from a
rospy.Timer when `~use_rospy_timer` (the negative control of clock_jump.test)."""
import rospy
from std_msgs.msg import Header

from mbzirc_ros_utils.periodic import PeriodicTimer

if __name__ == '__main__':
    rospy.init_node('ticker')
    pub = rospy.Publisher('tick', Header, queue_size=10)

    def tick(_event):
        pub.publish(Header(stamp=rospy.Time.now()))

    if rospy.get_param('~use_rospy_timer', False):
        timer = rospy.Timer(rospy.Duration(0.2), tick)
    else:
        timer = PeriodicTimer(0.2, tick, 'ticker')
    rospy.spin()
