#!/usr/bin/env python3
"""central_unit node: the Challenge 3 strategy, action client of every agent (see the package README)."""
import rospy

from mbzirc_central_unit.central_unit import CentralUnit


def main() -> None:
    rospy.init_node("central_unit")
    CentralUnit()
    rospy.spin()


if __name__ == "__main__":
    main()
