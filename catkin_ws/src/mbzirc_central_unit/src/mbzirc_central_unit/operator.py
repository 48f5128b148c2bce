"""The operator's commands to the central unit: start the trial, pause and resume its decisions.

`/central_unit/start_trial` (std_srvs/Trigger): with `~wait_for_start` true the central unit gives no goal
before it (the robots wait on the ground, as the original team's start services made them); without, the
trial starts at once. `/central_unit/pause` (std_srvs/SetBool): true = no new decisions (running tasks go
on), false = resume. Both appear in `/central_unit/status` as `started` and `paused`.
"""
from __future__ import annotations

import threading
from typing import Any


class OperatorGate:
    """Whether the central unit may decide (pure; `advertise` adds the ROS services)."""

    def __init__(self, wait_for_start: bool = False) -> None:
        self.lock = threading.Lock()
        self.started = not wait_for_start
        self.paused = False

    def deciding(self) -> bool:
        with self.lock:
            return self.started and not self.paused

    def start(self) -> str:
        with self.lock:
            was, self.started = self.started, True
        return 'the trial was already started' if was else 'trial started'

    def pause(self, paused: bool) -> str:
        with self.lock:
            was, self.paused = self.paused, bool(paused)
        if paused:
            return 'already paused' if was else 'paused: no new goals'
        return 'resumed' if was else 'was not paused'

    def status(self) -> dict:
        with self.lock:
            return {'started': self.started, 'paused': self.paused}

    def advertise(self) -> list:
        """The two services (std_srvs), logged as they are used."""
        import rospy
        from std_srvs.srv import SetBool, SetBoolResponse, Trigger, TriggerResponse

        def on_start(_req: Any) -> TriggerResponse:
            text = self.start()
            rospy.logwarn(f'central_unit: operator: {text}')
            return TriggerResponse(True, text)

        def on_pause(req: Any) -> SetBoolResponse:
            text = self.pause(req.data)
            rospy.logwarn(f'central_unit: operator: {text}')
            return SetBoolResponse(True, text)

        return [rospy.Service('/central_unit/start_trial', Trigger, on_start),
                rospy.Service('/central_unit/pause', SetBool, on_pause)]
