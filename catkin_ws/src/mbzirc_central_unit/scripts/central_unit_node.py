#!/usr/bin/env python3
"""central_unit node: the Challenge 3 strategy, action client of every agent (see the package README)."""
# the package first: it makes numpy single-threaded before rospy loads numpy
from mbzirc_central_unit.central_unit import CentralUnit
import rospy  # noqa: E402


def main() -> None:
    rospy.init_node("central_unit")
    CentralUnit()
    rospy.spin()


if __name__ == "__main__":
    main()
