#!/usr/bin/env python3
"""mission_recorder node: the referee of a simulated trial; writes summary.json and report.png."""
import rospy

from mbzirc_referee.recorder import MissionRecorder


def main() -> None:
    rospy.init_node("mission_recorder")
    MissionRecorder()
    rospy.spin()


if __name__ == "__main__":
    main()
