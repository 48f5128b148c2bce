"""Agent: the tasks, their action servers, the state machine thread and the request hand-over.

Why this shape (the thesis's design): an agent is a SMACH state machine with an idle `DEFAULT` state and
one state per task; every task is offered to the central unit as an actionlib action. The modules:
`agent_interface` (topics and services routed to the active task), `agent_task` (the task base),
`agent_state_machine` (DEFAULT + tasks) and this one. None imports rospy: ROS is reached through a
*backend* object (see `ros_backend.RosBackend`), so the whole framework runs in unit tests with a fake
backend and no ROS master.

.. note:: an agent runs one task at a time. A goal for another task while one runs is aborted with
   "busy: ..."; a new goal on the same task's server preempts the running goal (actionlib's simple
   server semantics), and the new goal then runs.
"""
from __future__ import annotations

import threading
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Optional

from . import constants as C
from .agent_interface import AgentInterface
from .agent_state_machine import AgentStateMachine
from .agent_task import AgentTask


@dataclass
class TaskSpec:
    """What add_task registered: the task state, its action type and how to read a goal."""
    name: str
    task: AgentTask
    action: Any                                     # e.g. mbzirc_comm_objs.msg.TakeOffAction
    gen_userdata: Callable[[Any, 'Agent'], Dict[str, Any]]
    result_type: Any = None
    feedback_type: Any = None


@dataclass
class Request:
    """A goal handed from an action server (or the agent itself) to the state machine."""
    name: str
    userdata: Dict[str, Any]
    server: Any = None
    done: threading.Event = field(default_factory=threading.Event)
    outcome: str = ''
    result: Dict[str, Any] = field(default_factory=dict)
    reason: str = ''                                # why it was preempted by the agent, if it was


class Agent:
    """An agent: tasks, their action servers, the state machine thread, data_feed and cost queries.

    Subclasses (UAV, UGV) add their tasks in __init__ and implement `safe_stop()`, `idle()`,
    `fill_data_feed(msg)` and `cost_to_go_to(pose)`.
    """

    def __init__(self, agent_id: str, backend: Any, namespace: str = '') -> None:
        self.agent_id = agent_id
        self.backend = backend
        self.namespace = namespace
        self.iface = AgentInterface(backend)
        self.iface.close()                    # no message reaches a callback before start(): the agent is built
        self.specs: Dict[str, TaskSpec] = {}
        self.sm: Optional[AgentStateMachine] = None
        self._lock = threading.Lock()
        self._pending: Optional[Request] = None
        self._wake = threading.Event()
        self._running: Optional[Request] = None
        self._servers: Dict[str, Any] = {}
        self._sm_thread: Optional[threading.Thread] = None
        self.active_sub_state = ''
        self.active_message = ''
        self.accepting = True            # False while the central unit's heartbeat is lost
        self.reject_reason = ''
        self.failed = ''                 # why the agent gave up (its state machine kept dying), '' if fine
        self.sm_beat: Optional[float] = None   # wall time the state machine last showed it runs (note_sm_alive)
        self._inject = False             # inject_fault() (test hook)

    # -- registration
    def add_task(self, name: str, task_class: type, action: Any, gen_userdata: Callable,
                 result_type: Any = None, feedback_type: Any = None, **task_args: Any) -> AgentTask:
        """Register a task offered as action `<name>_action` (call before start())."""
        if self.sm is not None:
            raise RuntimeError('add_task after start()')
        if name in self.specs:
            raise ValueError(f'task {name} added twice')
        task = task_class(name, self, **task_args)
        self.specs[name] = TaskSpec(name, task, action, gen_userdata, result_type, feedback_type)
        return task

    def add_sub_task(self, name: str, parent_task: str, child_task: type, task_args: Optional[dict] = None
                     ) -> AgentTask:
        """Give task parent_task a sub-task (an instance of child_task) it can run with call_task(name)."""
        parent = self.specs[parent_task].task if parent_task in self.specs else None
        if parent is None:
            raise ValueError(f'no task {parent_task}')
        child = child_task(f'{parent_task}/{name}', self, **(task_args or {}))
        parent.sub_tasks[name] = child
        return child

    def add_sub_task_to(self, parent: AgentTask, name: str, child_task: type,
                        task_args: Optional[dict] = None) -> AgentTask:
        """Like add_sub_task for a parent that is itself a sub-task (nested composition)."""
        child = child_task(f'{parent.name}/{name}', self, **(task_args or {}))
        parent.sub_tasks[name] = child
        return child

    # -- life
    def start(self) -> None:
        """Build the state machine, start its thread and the action servers; let the messages in."""
        self.iface.open()
        self.sm = AgentStateMachine(self, self.specs)
        self._sm_thread = self.backend.start_thread('agent_sm', self._run_sm)
        for name, spec in self.specs.items():
            self._servers[name] = self.backend.action_server(
                f'{name}_action', spec.action, lambda goal, n=name: self._execute_goal(n, goal))

    def _run_sm(self) -> None:
        """Run the state machine until shutdown. Why a loop: an exception that escapes a state (the idle
        state's `idle()`, a container bug) ends `execute()`; the thread used to end with it while data_feed
        still said idle and every goal waited forever (a zombie agent). Now the death is logged, the request
        in hand is aborted, and a new state machine starts, at most C.SM_MAX_RESTARTS times; after that the
        agent is marked failed (data_feed says so, goals are refused) instead of pretending to be idle."""
        restarts = 0
        while True:
            try:
                self.sm.execute()
                return                                   # ended normally: shutdown
            except Exception:
                self.backend.logerr(f'agent state machine died: {traceback.format_exc()}')
            if self.backend.is_shutdown():
                return
            self._abort_requests('the agent state machine died')
            restarts += 1
            if restarts > C.SM_MAX_RESTARTS:
                with self._lock:
                    self.failed = f'state machine died {restarts} times'
                self.backend.logerr(f'agent {self.agent_id} FAILED: {self.failed}; refusing goals')
                return
            self.backend.logwarn(f'agent state machine restarted ({restarts}/{C.SM_MAX_RESTARTS})')
            self.sm = AgentStateMachine(self, self.specs)

    def _abort_requests(self, why: str) -> None:
        """End the pending and running requests (their action clients get an abort) and stop the robot."""
        with self._lock:
            reqs = [r for r in (self._pending, self._running) if r is not None]
            self._pending = self._running = None
        for req in reqs:
            self.specs[req.name].task.request_preempt()
            req.outcome, req.result = C.ERROR, {'message': why}
            req.done.set()
        try:
            self.safe_stop()
        except Exception as e:  # noqa: BLE001 - logged; the restart goes on
            self.backend.logerr(f'safe stop after the state machine died failed: {e!r}')
        self.active_sub_state, self.active_message = '', ''

    def note_sm_alive(self) -> None:
        """The state machine's loops call this (idle state, task preempt checks, feedback): the agent's
        liveness (its data_feed) comes from the loop that does the work, not from a timer beside it."""
        self.sm_beat = self.backend.wall_time()

    def sm_silent_for(self) -> float:
        """Wall seconds since the state machine last showed it runs (0 before it first ran)."""
        return 0.0 if self.sm_beat is None else max(self.backend.wall_time() - self.sm_beat, 0.0)

    def inject_fault(self) -> None:
        """Test hook (the fault suite, `~fault_injection`): the state machine's next step raises, in the idle
        state or in the running task."""
        self._inject = True

    def raise_injected_fault(self) -> None:
        """Called by the idle state and by tasks at each step: raises once after `inject_fault()`."""
        if self._inject:
            self._inject = False
            raise RuntimeError('fault injected (test)')

    def shutdown(self) -> None:
        """Preempt the running task and stop the state machine (Ctrl+C)."""
        if self.sm is not None:
            self.sm.request_preempt()
        with self._lock:
            running = self._running
        if running is not None:
            self.specs[running.name].task.request_preempt()
        if self._sm_thread is not None:
            self._sm_thread.join(timeout=5.0)

    # -- requests
    def submit(self, name: str, userdata: Dict[str, Any], server: Any = None, force: bool = False) -> Request:
        """Hand a request to the state machine; raises RuntimeError('busy: ...') when one runs.

        force: the agent's own request (e.g. going home), accepted even while not accepting goals.
        """
        with self._lock:
            if self.failed:
                raise RuntimeError(f'agent failed: {self.failed}')
            if not self.accepting and not force:
                raise RuntimeError(f'not accepting goals: {self.reject_reason}')
            busy = self._running or self._pending
            if busy is not None:
                raise RuntimeError(f'busy: running task {busy.name}; cancel it first')
            req = Request(name, userdata, server)
            self._pending = req
            self._wake.set()
        return req

    def _take_request(self, timeout: float) -> Optional[Request]:
        self.backend.wait_event(self._wake, timeout)
        with self._lock:
            req = self._pending
            self._pending = None
            self._wake.clear()
            if req is not None:
                self._running = req
                self.specs[req.name].task.recall_preempt()   # a stale request of a finished goal
            return req

    def preempt_running(self, reason: str = '') -> Optional[str]:
        """Preempt the running task (if any), noting why; returns its name."""
        with self._lock:
            req = self._running
            if req is None:
                return None
            if reason and not req.reason:
                req.reason = reason
        self.specs[req.name].task.request_preempt()
        return req.name

    def running_task(self) -> str:
        """Name of the running top-level task, '' when idle."""
        with self._lock:
            return self._running.name if self._running else ''

    def _task_finished(self, task: AgentTask, outcome: str) -> None:
        with self._lock:
            req = self._running
            if req is None or self.specs.get(req.name) is None or self.specs[req.name].task is not task:
                return                      # a sub-task ended: its parent goes on
            self._running = None
        if outcome != C.SUCCESS:
            try:
                self.safe_stop()
            except Exception as e:
                self.backend.logerr(f'safe stop after {task.name} failed: {e!r}')
        req.outcome = outcome
        req.result = dict(task.result)
        if req.reason:
            req.result['message'] = f'{req.reason} ({req.result.get("message", "")})'
        self.active_sub_state = ''
        self.active_message = ''
        req.done.set()

    # -- actions
    def _execute_goal(self, name: str, goal: Any) -> None:
        """execute_cb of the action server of task name (runs in that server's thread)."""
        spec = self.specs[name]
        server = self._servers[name]
        try:
            userdata = spec.gen_userdata(goal, self)
        except (ValueError, TypeError, KeyError) as e:
            server.set_aborted(self._make_result(spec, {'message': f'bad goal: {e}'}), f'bad goal: {e}')
            return
        try:
            req = self.submit(name, userdata, server)
        except RuntimeError as e:
            server.set_aborted(self._make_result(spec, {'message': str(e)}), str(e))
            return
        preempt_sent = False
        while not self.backend.wait_event(req.done, 1.0 / C.CONTROL_RATE_HZ):
            if not preempt_sent and (server.is_preempt_requested() or self.backend.is_shutdown()):
                preempt_sent = True
                with self._lock:
                    if self._pending is req:          # not started yet: withdraw it
                        self._pending = None
                        req.outcome = C.PREEMPTED
                        req.result = {'message': f'{name} cancelled before it started'}
                        req.done.set()
                        break
                spec.task.request_preempt()
        result = self._make_result(spec, req.result)
        text = req.result.get('message', '')
        if req.outcome == C.SUCCESS:
            server.set_succeeded(result, text)
        elif req.outcome == C.PREEMPTED and not req.reason:
            server.set_preempted(result, text)
        else:
            server.set_aborted(result, text)

    @staticmethod
    def _make_result(spec: TaskSpec, fields: Dict[str, Any]) -> Any:
        if spec.result_type is None:
            return None
        res = spec.result_type()
        for k, v in fields.items():
            if hasattr(res, k):
                setattr(res, k, v)
        return res

    def publish_feedback(self, task_name: str, state: str, message: str) -> None:
        """Feedback of the active task to its action client, data_feed and the log."""
        self.note_sm_alive()
        self.active_sub_state, self.active_message = state, message
        with self._lock:
            req = self._running
        self.backend.loginfo_throttle(2.0, f'[{task_name}] {state}: {message}')
        if req is None or req.server is None:
            return
        spec = self.specs[req.name]
        if spec.feedback_type is not None:
            fb = spec.feedback_type()
            fb.state, fb.message = state, message
            req.server.publish_feedback(fb)

    # -- to override by robot agents
    def safe_stop(self) -> None:
        """Bring the robot to a safe state after a task was preempted or failed."""

    def idle(self) -> None:
        """Called at the control rate while no task runs."""
