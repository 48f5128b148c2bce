"""ROS adapter of the shared-region manager: serves /ask_for_region and /free_regions.

Optional debug output: `~publish_markers` (false) publishes the reserved boxes as a MarkerArray on
`regions` at 1 Hz (for rviz).
"""
from __future__ import annotations

import math

import rospy
from mbzirc_comm_objs.srv import (AskForRegion, AskForRegionResponse, FreeRegions, FreeRegionsResponse)

from .core import RegionManager


class RegionManagerNode:
    """Services `ask_for_region` and `free_regions` (relative names: put the node in the root ns)."""

    def __init__(self) -> None:
        self.core = RegionManager()
        self.ask_srv = rospy.Service('ask_for_region', AskForRegion, self.on_ask)
        self.free_srv = rospy.Service('free_regions', FreeRegions, self.on_free)
        self.markers = None
        if rospy.get_param('~publish_markers', False):
            from visualization_msgs.msg import MarkerArray
            self.markers = rospy.Publisher('regions', MarkerArray, queue_size=1)
            self.timer = rospy.Timer(rospy.Duration(1.0), self.publish_markers)

    def on_ask(self, req: AskForRegion._request_class) -> AskForRegionResponse:
        """Grant the box unless it overlaps another agent's box."""
        lo = (req.min_corner.point.x, req.min_corner.point.y, req.min_corner.point.z)
        hi = (req.max_corner.point.x, req.max_corner.point.y, req.max_corner.point.z)
        for frame in (req.min_corner.header.frame_id, req.max_corner.header.frame_id):
            if frame not in ('', 'arena'):
                rospy.logerr_throttle(5.0, f'ask_for_region from {req.agent_id}: frame {frame!r} is not arena')
                return AskForRegionResponse(success=False)
        ok, why = self.core.ask(req.agent_id, req.label, lo, hi)
        if not ok and not all(map(math.isfinite, lo + hi)):
            rospy.logerr_throttle(5.0, f'ask_for_region from {req.agent_id}: {why}')
        rospy.logdebug(f'ask_for_region {req.agent_id}/{req.label}: {why}')
        return AskForRegionResponse(success=ok)

    def on_free(self, req: FreeRegions._request_class) -> FreeRegionsResponse:
        """Free one box of the agent, or all of them."""
        return FreeRegionsResponse(success=self.core.free(req.agent_id, req.label, req.free_all))

    def publish_markers(self, _event=None) -> None:
        """The reserved boxes as translucent cubes (namespace = agent id)."""
        from visualization_msgs.msg import Marker, MarkerArray
        arr = MarkerArray()
        clear = Marker(action=Marker.DELETEALL)
        arr.markers.append(clear)
        for i, ((agent, label), (lo, hi)) in enumerate(sorted(self.core.regions().items())):
            m = Marker(type=Marker.CUBE, action=Marker.ADD, id=i, ns=f'{agent}/{label}')
            m.header.frame_id = 'arena'
            m.header.stamp = rospy.Time.now()
            c = (lo + hi) / 2.0
            m.pose.position.x, m.pose.position.y, m.pose.position.z = c
            m.pose.orientation.w = 1.0
            m.scale.x, m.scale.y, m.scale.z = hi - lo
            m.color.r, m.color.g, m.color.b, m.color.a = 0.2, 0.5, 1.0, 0.25
            arr.markers.append(m)
        self.markers.publish(arr)
