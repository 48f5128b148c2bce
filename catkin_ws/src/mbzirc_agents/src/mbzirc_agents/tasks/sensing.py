"""SensedObjects: the latest detections of the robot's own detectors, for the tasks' control loops.

Why a task-dependent subscription: only the task that centres a hole or a ground fire needs
`sensed_objects` at full rate; the AgentInterface routes it to that task while it runs.
"""
from __future__ import annotations

import math
import threading
from typing import NamedTuple, Optional

import numpy as np
from mbzirc_comm_objs.msg import ObjectDetectionList

from .. import constants as C
from ..control import body_to_world, world_to_body
from ..agent_task import AgentTask

CAM_OFFSET_X = 0.15      # base_link -> camera_color_optical_frame (docs/interfaces.md)


class Hole(NamedTuple):
    """A circle of the circle detector, in the body frame of the current pose.

    opening: m the circle's middle lies behind its rim (circle_detector's point_of_interest): ~0.3 for
    the real hole, ~0 for a painted decoy, NaN unknown.
    """
    body: np.ndarray
    radius: float
    opening: float


class SensedObjects:
    """Latest detections of the robot's own detectors, kept by a task-dependent callback."""

    def __init__(self, task: AgentTask) -> None:
        self.task = task
        self.lock = threading.Lock()
        self.holes: list = []            # (arena point at the image's time, radius m, opening m)
        self.holes_time = -1e9
        self.fire: Optional[tuple] = None  # (arena position, body relative position, camera direction)
        self.fire_time = -1e9
        task.iface.add_subscriber(task.name, 'sensed_objects', ObjectDetectionList, self.on_msg)

    def on_msg(self, msg: ObjectDetectionList) -> None:
        """Split holes (converted to the body frame) and fires."""
        a = self.task.agent
        holes = []
        now = a.backend.now()
        for d in msg.objects:
            # age from the image stamp: a detector lagging on a busy CPU must not steer with old images
            stamp = d.header.stamp.to_sec() or msg.stamp.to_sec() or now
            p = d.pose.pose.position
            if not all(map(math.isfinite, (p.x, p.y, p.z))):
                a.backend.logerr_throttle(5.0, 'sensed_objects: NaN position, ignored')
                continue
            if d.type == C.TYPE_HOLE:
                # placed in the arena with the pose when the image was taken: the UAV moves meanwhile
                w = self._to_world(d.header.frame_id, (p.x, p.y, p.z), stamp)
                if w is not None:
                    holes.append((w, float(d.scale.x), self._opening(d)))
            elif d.type == C.TYPE_FIRE:
                r = d.relative_position
                with self.lock:
                    self.fire = ((p.x, p.y, p.z), (r.x, r.y, r.z), d.image_detection.camera_direction)
                    self.fire_time = stamp
        if holes:
            with self.lock:
                self.holes, self.holes_time = holes, stamp

    @staticmethod
    def _opening(d) -> float:
        """Depth behind the rim seen through the circle (optical z), NaN when the detector had none."""
        q = d.point_of_interest
        if q.z == 0.0 or not math.isfinite(q.z):
            return math.nan
        return float(q.z - d.pose.pose.position.z)

    def _to_world(self, frame: str, p, stamp: float) -> Optional[np.ndarray]:
        frame = frame.lstrip('/')
        if frame in ('', C.GLOBAL_FRAME):
            return np.array(p, dtype=float)
        if frame.endswith('optical_frame'):               # x right, y down, z forward
            body = np.array([p[2] + CAM_OFFSET_X, -p[0], -p[1]])
        elif frame.endswith('base_link'):
            body = np.array(p, dtype=float)
        else:
            self.task.agent.backend.logerr_throttle(5.0, f'sensed_objects: hole in unknown frame {frame!r}')
            return None
        pose = self.task.agent.pose_at(stamp)
        return pose[:3] + body_to_world(body, pose[3])

    def clear(self) -> None:
        """Forget every detection: a new run of the task must not steer with the last run's."""
        with self.lock:
            self.holes, self.holes_time = [], -1e9
            self.fire, self.fire_time = None, -1e9

    def recent_holes(self, max_age: float) -> list:
        """The circles of the last detection (if at most max_age s old) as Holes seen from the pose now."""
        with self.lock:
            if self.task.agent.backend.now() - self.holes_time > max_age:
                return []
            holes = list(self.holes)
        pose = self.task.agent.position()
        return [Hole(world_to_body(w - pose[:3], pose[3]), r, o) for w, r, o in holes]

    def latest_fire(self) -> tuple:
        """(fire, stamp) of the last fire detection, read together: (None, -1e9) without one. The stamp is
        its image's, for the pose the robot had when it was taken (RobotAgent.pose_at)."""
        with self.lock:
            return self.fire, self.fire_time

    def recent_fire(self, max_age: float) -> Optional[tuple]:
        fire, stamp = self.latest_fire()
        return fire if self.task.agent.backend.now() - stamp <= max_age else None
