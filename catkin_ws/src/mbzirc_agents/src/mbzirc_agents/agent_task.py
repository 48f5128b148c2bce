"""AgentTask: the base of every task (a smach State with outcomes success / error / preempted), and the
exceptions a task's run() raises to end it.
"""
from __future__ import annotations

import threading
import traceback
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Optional

import smach

from . import constants as C

if TYPE_CHECKING:
    from .agent import Agent


class TaskPreempted(Exception):
    """Raised inside a task's run() by helpers when a preemption was requested."""


class TaskError(Exception):
    """Raised inside a task's run() to end it with outcome error and this message."""


class MoveTimedOut(TaskError):
    """A go-to (RobotAgent.move_to) not there in its time: a caller for whom the move is best effort catches
    this one and lets every other TaskError (crashed, no trusted pose) end the task."""


class AgentTask(smach.State):
    """Base of every task: a smach State whose outcomes are success / error / preempted.

    Subclasses set `INPUT_KEYS` and implement `run(ud)`, returning an outcome (or raising TaskError /
    TaskPreempted); they put extra result fields in `self.result` and describe what they do with
    `self.feedback(state, message)`.

    Args:
        name: the task's name (action `<name>_action`); agent: the Agent; args: task_args of add_task.
    """
    INPUT_KEYS: List[str] = []

    def __init__(self, name: str, agent: 'Agent', **args: Any) -> None:
        super().__init__(outcomes=list(C.TASK_OUTCOMES), input_keys=list(self.INPUT_KEYS))
        self.name = name
        self.agent = agent
        self.iface = agent.iface
        self.args = args
        self.result: Dict[str, Any] = {}
        self.sub_tasks: Dict[str, 'AgentTask'] = {}
        self._child: Optional['AgentTask'] = None
        self._sub_lock = threading.Lock()

    # -- to implement
    def run(self, ud: Any) -> str:
        """Do the task; return one of constants.TASK_OUTCOMES."""
        raise NotImplementedError

    # -- smach
    def execute(self, ud: Any) -> str:
        """Runs run() with the bookkeeping every task needs (why final: see the class docstring)."""
        self.result = {'message': ''}
        self.iface.push_active(self.name)
        outcome = C.ERROR
        try:
            if self.preempt_requested():
                raise TaskPreempted()
            outcome = self.run(ud)
            if outcome not in C.TASK_OUTCOMES:
                self.result['message'] = f'task returned unknown outcome {outcome!r}'
                outcome = C.ERROR
        except TaskPreempted:
            outcome = C.PREEMPTED
        except TaskError as e:
            outcome = C.ERROR
            self.result['message'] = str(e)
        except Exception as e:  # a bug in a task must not kill the agent
            outcome = C.ERROR
            self.result['message'] = f'{self.name} failed: {e!r}'
            self.agent.backend.logerr(f'{self.name}: {traceback.format_exc()}')
        finally:
            self.iface.pop_active(self.name)
        if outcome == C.PREEMPTED:
            self.service_preempt()
            if not self.result.get('message'):
                self.result['message'] = f'{self.name} preempted'
        elif not self.result.get('message'):
            self.result['message'] = f'{self.name}: {outcome}'
        self.agent._task_finished(self, outcome)
        return outcome

    def request_preempt(self) -> None:
        """Preempt this task and the sub-task it is running."""
        super().request_preempt()
        with self._sub_lock:
            child = self._child
        if child is not None:
            child.request_preempt()

    # -- helpers for run()
    def feedback(self, state: str, message: str) -> None:
        """Say what the robot is doing (action feedback, data_feed, log)."""
        self.agent.publish_feedback(self.name, state, message)

    def check_preempt(self) -> None:
        """Raise TaskPreempted when a preemption was requested (and an injected fault, see inject_fault)."""
        self.agent.note_sm_alive()
        self.agent.raise_injected_fault()
        if self.preempt_requested():
            raise TaskPreempted()

    def sleep(self, seconds: float) -> None:
        """Sleep (sim time aware) in steps, raising TaskPreempted on preemption."""
        end = self.agent.backend.now() + seconds
        step = 1.0 / C.CONTROL_RATE_HZ
        while True:
            self.check_preempt()
            left = end - self.agent.backend.now()
            if left <= 0 or self.agent.backend.is_shutdown():
                return
            self.agent.backend.sleep(min(step, left))

    def wait_for(self, condition: Callable[[], bool], timeout: float, what: str) -> None:
        """Poll condition at the control rate; TaskError after timeout s (why: never hang a task)."""
        end = self.agent.backend.now() + timeout
        while not condition():
            self.check_preempt()
            if self.agent.backend.now() > end or self.agent.backend.is_shutdown():
                raise TaskError(f'timeout ({timeout:.0f} s) waiting for {what}')
            self.agent.backend.sleep(1.0 / C.CONTROL_RATE_HZ)

    def call_task(self, name: str, userdata: Dict[str, Any]) -> str:
        """Run sub-task name (registered with add_sub_task) with userdata; returns its outcome.

        Its result goes to `self.last_sub_result`. A preemption of this task preempts the sub-task.
        """
        child = self.sub_tasks.get(name)
        if child is None:
            raise TaskError(f'{self.name}: no sub-task {name}')
        self.check_preempt()
        ud = smach.UserData()
        for k, v in userdata.items():
            ud[k] = v
        child.recall_preempt()
        with self._sub_lock:
            self._child = child
        self.check_preempt()
        try:
            outcome = child.execute(ud)
        finally:
            with self._sub_lock:
                self._child = None
        self.last_sub_result = dict(child.result)
        if outcome == C.PREEMPTED and self.preempt_requested():
            raise TaskPreempted()
        return outcome

    def call_task_or_raise(self, name: str, userdata: Dict[str, Any], context: str = '') -> None:
        """call_task, and TaskError with the sub-task's message (after `context: ` when given) unless it
        succeeded: the usual way a task runs a step it cannot go on without."""
        if self.call_task(name, userdata) != C.SUCCESS:
            message = self.last_sub_result.get('message') or f'{name} failed'
            raise TaskError(f'{context}: {message}' if context else message)
