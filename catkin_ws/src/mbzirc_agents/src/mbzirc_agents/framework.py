"""The agent framework: AgentInterface, AgentTask, AgentStateMachine and Agent.

Why this shape (the thesis's design): an agent is a SMACH state machine with an idle `DEFAULT` state and
one state per task; every task is offered to the central unit as an actionlib action; a task only
coordinates components (UAL, actuators, detectors, estimator, region manager) through the
`AgentInterface`, which routes each message or request to the task that is active now.

Nothing here imports rospy: ROS is reached through a *backend* object (see `ros_backend.RosBackend`), so
the whole framework runs in unit tests with a fake backend and no ROS master.

.. note:: an agent runs one task at a time. A goal for another task while one runs is aborted with
   "busy: ..."; a new goal on the same task's server preempts the running goal (actionlib's simple
   server semantics), and the new goal then runs.
"""
from __future__ import annotations

import threading
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional

import smach

from . import constants as C


# ---- AgentInterface ------------------------------------------------------------------------------------
class AgentInterface:
    """Owns the node's publishers, subscribers, service servers and clients.

    A subscriber or service is created once per name; tasks register callbacks on it. A message goes to
    the callbacks of the tasks active now (a task and the sub-tasks it is running) and to the always-on
    callbacks (task None). A service request goes to the callback of the innermost active task that
    registered one, else to the service's default (inactive) callback.
    """

    def __init__(self, backend: Any) -> None:
        self.backend = backend
        self._subs: Dict[str, dict] = {}
        self._services: Dict[str, dict] = {}
        self._pubs: Dict[str, Any] = {}
        self._clients: Dict[str, Any] = {}
        self._active: List[str] = []          # stack: top-level task, then its running sub-tasks
        self._demands: Dict[str, list] = {}   # task name -> [(topic, type)] subscribed only while it runs
        self._demand_subs: Dict[str, list] = {}
        self._lock = threading.Lock()

    # -- activity
    def push_active(self, task_name: str) -> None:
        """A task (or sub-task) starts: its callbacks receive data from now on, its demands open."""
        with self._lock:
            self._active.append(task_name)
            demands = list(self._demands.get(task_name, []))
        subs = []
        for topic, msg_type in demands:
            try:
                subs.append((topic, self.backend.subscriber(topic, msg_type, lambda _msg: None)))
            except Exception as e:  # noqa: BLE001 - a producer switched off costs time, not the task
                self.backend.logerr(f'{task_name}: could not subscribe to {topic}: {e!r}')
        if subs:
            with self._lock:
                self._demand_subs.setdefault(task_name, []).extend(subs)

    def pop_active(self, task_name: str) -> None:
        """A task ends: its callbacks stop receiving, its demands close."""
        with self._lock:
            if task_name in self._active:
                self._active.remove(task_name)
            subs = self._demand_subs.pop(task_name, [])
        for _topic, sub in subs:
            unregister = getattr(sub, 'unregister', None)
            if unregister is not None:
                unregister()

    def add_demand(self, task_name: str, topic: str, msg_type: Any) -> None:
        """Subscribe to topic only while task_name runs, to switch on a lazy producer.

        Why: a lazy node (circle_detector ~lazy) works only while one of its outputs has a subscriber, and
        the always-on `sensed_objects` cannot say so (the estimator listens to it all the time). The
        subscription carries no data to the task; its existence is the request.
        """
        with self._lock:
            self._demands.setdefault(task_name, []).append((topic, msg_type))

    def demanded_topics(self) -> List[str]:
        """Topics subscribed now because a running task demands them."""
        with self._lock:
            return [topic for subs in self._demand_subs.values() for topic, _ in subs]

    def active_tasks(self) -> List[str]:
        """Names of the active tasks, outermost first."""
        with self._lock:
            return list(self._active)

    # -- topics
    def add_subscriber(self, task_name: Optional[str], topic: str, msg_type: Any,
                       callback: Callable[[Any], None]) -> None:
        """Route messages of topic to callback while task_name is active (always when None)."""
        with self._lock:
            entry = self._subs.get(topic)
            if entry is None:
                entry = {'type': msg_type, 'callbacks': {}}
                self._subs[topic] = entry
                create = True
            else:
                if entry['type'] is not msg_type:
                    raise TypeError(f'topic {topic} already subscribed with another type')
                create = False
            entry['callbacks'].setdefault(task_name, []).append(callback)
        if create:
            self.backend.subscriber(topic, msg_type, lambda msg, t=topic: self._dispatch(t, msg))

    def _dispatch(self, topic: str, msg: Any) -> None:
        with self._lock:
            entry = self._subs[topic]
            names = [None] + list(self._active)
            callbacks = [cb for n in names for cb in entry['callbacks'].get(n, [])]
        for cb in callbacks:
            try:
                cb(msg)
            except Exception as e:   # a bad message must not kill the subscriber thread
                self.backend.logerr_throttle(5.0, f'callback for {topic} failed: {e!r}')

    def add_publisher(self, topic: str, msg_type: Any, latch: bool = False) -> Any:
        """The (shared) publisher of topic."""
        with self._lock:
            if topic not in self._pubs:
                self._pubs[topic] = self.backend.publisher(topic, msg_type, latch)
            return self._pubs[topic]

    # -- services
    def add_service_server(self, task_name: Optional[str], name: str, srv_type: Any,
                           callback: Optional[Callable[[Any], Any]] = None,
                           default_callback: Optional[Callable[[Any], Any]] = None) -> None:
        """Serve name: requests go to task_name's callback while it is active, else to the default."""
        with self._lock:
            entry = self._services.get(name)
            create = entry is None
            if create:
                entry = {'type': srv_type, 'callbacks': {}, 'default': None}
                self._services[name] = entry
            if callback is not None:
                entry['callbacks'][task_name] = callback
            if default_callback is not None:
                entry['default'] = default_callback
        if create:
            self.backend.service(name, srv_type, lambda req, n=name: self._serve(n, req))

    def _serve(self, name: str, req: Any) -> Any:
        with self._lock:
            entry = self._services[name]
            cb = None
            for n in reversed(self._active):
                if n in entry['callbacks']:
                    cb = entry['callbacks'][n]
                    break
            if cb is None:
                cb = entry['callbacks'].get(None) or entry['default']
        if cb is None:
            raise RuntimeError(f'service {name}: no active task serves it and no default callback')
        return cb(req)

    def add_client(self, name: str, srv_type: Any) -> Any:
        """The (shared) client of service name."""
        with self._lock:
            if name not in self._clients:
                self._clients[name] = self.backend.service_proxy(name, srv_type)
            return self._clients[name]


# ---- tasks ---------------------------------------------------------------------------------------------
class TaskPreempted(Exception):
    """Raised inside a task's run() by helpers when a preemption was requested."""


class TaskError(Exception):
    """Raised inside a task's run() to end it with outcome error and this message."""


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
        """Raise TaskPreempted when a preemption was requested."""
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


# ---- state machine -------------------------------------------------------------------------------------
class DefaultState(smach.State):
    """The idle state: waits for a request and leaves with the requested task's name."""

    def __init__(self, agent: 'Agent', task_names: List[str], keys: List[str]) -> None:
        super().__init__(outcomes=list(task_names) + [C.SHUTDOWN_OUTCOME], output_keys=list(keys))
        self.agent = agent

    def execute(self, ud: Any) -> str:
        """Idle until a goal arrives; keeps the robot safe meanwhile (the agent's idle())."""
        while not self.preempt_requested() and not self.agent.backend.is_shutdown():
            req = self.agent._take_request(timeout=1.0 / C.CONTROL_RATE_HZ)
            if req is not None:
                for k, v in req.userdata.items():
                    ud[k] = v
                return req.name
            self.agent.idle()
        if self.preempt_requested():
            self.service_preempt()
        return C.SHUTDOWN_OUTCOME


class AgentStateMachine(smach.StateMachine):
    """DEFAULT plus one state per task; every task outcome returns to DEFAULT."""

    def __init__(self, agent: 'Agent', specs: Dict[str, TaskSpec]) -> None:
        super().__init__(outcomes=[C.SM_END])
        keys = sorted({k for s in specs.values() for k in s.task.get_registered_input_keys()})
        with self:
            smach.StateMachine.add(C.DEFAULT_STATE, DefaultState(agent, list(specs), keys),
                                   transitions={**{n: n for n in specs}, C.SHUTDOWN_OUTCOME: C.SM_END})
            for name, spec in specs.items():
                smach.StateMachine.add(name, spec.task,
                                       transitions={o: C.DEFAULT_STATE for o in C.TASK_OUTCOMES})


# ---- agent ---------------------------------------------------------------------------------------------
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
        """Build the state machine, start its thread and the action servers."""
        self.sm = AgentStateMachine(self, self.specs)
        self._sm_thread = threading.Thread(target=self._run_sm, name='agent_sm', daemon=True)
        self._sm_thread.start()
        for name, spec in self.specs.items():
            self._servers[name] = self.backend.action_server(
                f'{name}_action', spec.action, lambda goal, n=name: self._execute_goal(n, goal))

    def _run_sm(self) -> None:
        try:
            self.sm.execute()
        except Exception:
            self.backend.logerr(f'agent state machine died: {traceback.format_exc()}')

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
