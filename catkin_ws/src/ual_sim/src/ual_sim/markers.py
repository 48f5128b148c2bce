"""RViz markers of the simulation: building boxes, robots, fires (colour = state), water jets, blankets."""
from __future__ import annotations

import math

import rospy
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

from . import constants as C
from .fires import GROUND
from .sim import Simulation


def _marker(ns: str, mid: int, mtype: int, stamp: rospy.Time, pos, scale, rgba) -> Marker:
    m = Marker(header=Header(stamp=stamp, frame_id=C.FRAME_ARENA), ns=ns, id=mid, type=mtype, action=Marker.ADD)
    m.pose = Pose(Point(*pos), Quaternion(0, 0, 0, 1))
    m.scale = Vector3(*scale)
    m.color = ColorRGBA(*rgba)
    return m


def build_markers(sim: Simulation, stamp: rospy.Time) -> MarkerArray:
    """One MarkerArray with everything; cheap enough at 2 Hz (about a hundred markers)."""
    w, out = sim.world, []
    for i, (lo, hi) in enumerate(zip(w.bmin, w.bmax)):
        c = w.box_color[i] / 255.0
        out.append(_marker("building", i, Marker.CUBE, stamp, (lo + hi) / 2, hi - lo, (c[0], c[1], c[2], 0.6)))
    for k, f in enumerate(sim.fires.fires):
        if f.kind == GROUND:
            size, mtype = (2 * C.GROUND_PLATE_RADIUS, 2 * C.GROUND_PLATE_RADIUS, 0.05), Marker.CYLINDER
        else:
            size, mtype = (0.4, 0.4, 0.4), Marker.SPHERE
        if not f.active:
            rgba = (0.3, 0.3, 0.3, 0.8)
        elif f.extinguished:
            rgba = (0.1, 0.4, 1.0, 1.0)
        else:
            rgba = (1.0, 0.3 * f.progress, 0.0, 1.0)
        out.append(_marker("fires", k, mtype, stamp, f.holder.position, size, rgba))
    for rid, r in sorted(sim.robots.items()):
        rgba = (0.2, 0.2, 0.2, 1.0) if r.crashed else ((0.1, 0.8, 0.1, 1.0) if r.is_uav else (0.8, 0.6, 0.1, 1.0))
        size = (2 * r.radius, 2 * r.radius, 0.3) if r.is_uav else (1.5, 1.2, C.UGV_HEIGHT)
        m = _marker("robots", rid, Marker.CYLINDER if r.is_uav else Marker.CUBE, stamp,
                    r.pos + [0, 0, size[2] / 2], size, rgba)
        m.pose.orientation = Quaternion(0, 0, math.sin(r.yaw / 2), math.cos(r.yaw / 2))
        out.append(m)
        label = _marker("labels", rid, Marker.TEXT_VIEW_FACING, stamp, r.pos + [0, 0, 1.0], (0, 0, 0.5), (1, 1, 1, 1))
        label.text = f"{C.robot_ns(rid)} {r.water:.1f}L" + (" B" if r.blanket else "")
        out.append(label)
        jet = _marker("jets", rid, Marker.LINE_STRIP, stamp, (0, 0, 0), (0.05, 0, 0), (0.2, 0.5, 1.0, 0.9))
        if rid in sim.jets:
            p, _ = r.nozzle()
            jet.points = [Point(*p), Point(*sim.jets[rid].end)]
        else:
            jet.action = Marker.DELETE
        out.append(jet)
    for k, b in enumerate(sim.blankets):
        out.append(_marker("blankets", k, Marker.CUBE, stamp, b.position, (C.BLANKET_SIZE, C.BLANKET_SIZE, 0.02),
                           (0.6, 0.6, 0.6, 1.0)))
    return MarkerArray(markers=out)
