"""SensedObjects: the latest detections of the robot's own detectors, for the tasks' control loops.

Why a task-dependent subscription: only the task that centres a hole or a ground fire needs
`sensed_objects` at full rate; the AgentInterface routes it to that task while it runs.
"""
from __future__ import annotations

import math
import threading
from typing import Optional

import numpy as np
from mbzirc_comm_objs.msg import ObjectDetectionList

from .. import constants as C
from ..control import world_to_body
from ..framework import AgentTask

CAM_OFFSET_X = 0.15      # base_link -> camera_color_optical_frame (docs/interfaces.md)


class SensedObjects:
    """Latest detections of the robot's own detectors, kept by a task-dependent callback."""

    def __init__(self, task: AgentTask) -> None:
        self.task = task
        self.lock = threading.Lock()
        self.holes: list = []            # (body-frame point, radius m)
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
                b = self._to_body(d.header.frame_id, (p.x, p.y, p.z))
                if b is not None:
                    holes.append((b, float(d.scale.x)))
            elif d.type == C.TYPE_FIRE:
                r = d.relative_position
                with self.lock:
                    self.fire = ((p.x, p.y, p.z), (r.x, r.y, r.z), d.image_detection.camera_direction)
                    self.fire_time = stamp
        if holes:
            with self.lock:
                self.holes, self.holes_time = holes, stamp

    def _to_body(self, frame: str, p) -> Optional[np.ndarray]:
        frame = frame.lstrip('/')
        if frame.endswith('optical_frame'):               # x right, y down, z forward
            return np.array([p[2] + CAM_OFFSET_X, -p[0], -p[1]])
        if frame.endswith('base_link'):
            return np.array(p)
        if frame in ('', C.GLOBAL_FRAME):
            pose = self.task.agent.position()
            return world_to_body(np.array(p) - pose[:3], pose[3])
        self.task.agent.backend.logerr_throttle(5.0, f'sensed_objects: hole in unknown frame {frame!r}')
        return None

    def recent_holes(self, max_age: float) -> list:
        with self.lock:
            return list(self.holes) if self.task.agent.backend.now() - self.holes_time <= max_age else []

    def recent_fire(self, max_age: float) -> Optional[tuple]:
        with self.lock:
            return self.fire if self.task.agent.backend.now() - self.fire_time <= max_age else None
