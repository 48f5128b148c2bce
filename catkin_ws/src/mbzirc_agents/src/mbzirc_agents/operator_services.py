"""The operator's commands to one agent: the ground station's buttons, or `rosservice call`.

- `operator/go_home` (std_srvs/Trigger): stop the running task, refuse the central unit's goals from now on
  (it gives the robot's work to the others), and go home: a UAV flies home and lands (go_home_and_refill),
  the UGV drives to its home pose (go_to).
- `operator/land` (std_srvs/Trigger): emergency: stop the running task, refuse goals, and (UAV) land where
  it is, through the UAL.
- `operator/release` (std_srvs/Trigger): accept the central unit's goals again.

The agent's own requests (force=True: going home) are never refused. Installed by agent_node.
"""
from __future__ import annotations

import time
from typing import Any, Callable

import rospy
from std_srvs.srv import Trigger, TriggerResponse

STOP_TIMEOUT_S = 20.0   # wall s for the running task to stop after a preempt (or a take-off to end)


class OperatorServices:
    """Serves the operator's commands for `agent` (a RobotAgent) in its namespace `ns`."""

    def __init__(self, agent: Any, ns: str) -> None:
        self.agent = agent
        self.ns = ns.rstrip('/')
        self.hold_reason = ''
        self._submit: Callable[..., Any] = agent.submit
        agent.submit = self._gated_submit      # the action servers' goals pass through the operator's hold
        self.services = [rospy.Service(f'{self.ns}/operator/{name}', Trigger, handler) for name, handler in
                         (('go_home', self.on_go_home), ('land', self.on_land), ('release', self.on_release))]

    def _gated_submit(self, name: str, userdata: dict, server: Any = None, force: bool = False) -> Any:
        if self.hold_reason and not force:
            raise RuntimeError(f'not accepting goals: {self.hold_reason}')
        return self._submit(name, userdata, server, force)

    def _hold(self, reason: str) -> bool:
        """Refuse goals from now on, stop the running task; True once the agent is idle."""
        self.hold_reason = reason
        rospy.logwarn(f'operator: {reason}')
        if self.agent.running_task() != 'take_off':   # a take-off ends by itself in seconds; preempted, it
            self.agent.preempt_running(f'operator: {reason}')   # left the UAL taking off, the UAV hovering
        deadline = time.monotonic() + STOP_TIMEOUT_S
        while self.agent.running_task() and time.monotonic() < deadline:
            time.sleep(0.05)
        return not self.agent.running_task()

    def on_go_home(self, _req: Any) -> TriggerResponse:
        if not self._hold('recalled home by the operator'):
            return TriggerResponse(False, 'the running task did not stop')
        if 'go_home_and_refill' in self.agent.specs:
            task, userdata = 'go_home_and_refill', {}
        elif self.agent.home is not None:
            task, userdata = 'go_to', {'waypoint': (tuple(float(v) for v in self.agent.home), None)}
        else:
            return TriggerResponse(False, 'home unknown: stopped where it is')
        try:
            self._submit(task, userdata, force=True)
        except RuntimeError as e:
            return TriggerResponse(False, f'cannot go home: {e}')
        return TriggerResponse(True, f'going home ({task}); goals refused until operator/release')

    def on_land(self, _req: Any) -> TriggerResponse:
        stopped = self._hold('emergency land by the operator')
        if self.agent.ROBOT_TYPE != 'uav':
            return TriggerResponse(stopped, 'stopped' if stopped else 'the running task did not stop')
        from uav_abstraction_layer.srv import Land
        try:
            rospy.wait_for_service(f'{self.ns}/ual/land', 3.0)
            rospy.ServiceProxy(f'{self.ns}/ual/land', Land)(blocking=False)
        except (rospy.ROSException, rospy.ServiceException) as e:
            return TriggerResponse(False, f'UAL land failed: {e}')
        return TriggerResponse(True, 'landing' + ('' if stopped else ' (the task had not stopped yet)'))

    def on_release(self, _req: Any) -> TriggerResponse:
        was, self.hold_reason = self.hold_reason, ''
        rospy.loginfo('operator: goals accepted again')
        return TriggerResponse(True, f'released ({was})' if was else 'was not held')
