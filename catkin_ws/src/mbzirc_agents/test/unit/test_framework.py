"""Agent framework with a fake backend: dispatch, busy rejection, preemption, sub-tasks, bad goals."""
import math
from types import SimpleNamespace

import pytest

import smach  # noqa: F401,E402  (the workspace's smach, pure Python)

from fake_backend import FakeBackend  # noqa: E402
from mbzirc_agents import constants as C  # noqa: E402
from mbzirc_agents.agent import Agent  # noqa: E402
from mbzirc_agents.agent_interface import AgentInterface  # noqa: E402
from mbzirc_agents.agent_task import AgentTask, TaskError  # noqa: E402


class Result(SimpleNamespace):
    def __init__(self):
        super().__init__(message='', value=0.0)


class Feedback(SimpleNamespace):
    def __init__(self):
        super().__init__(state='', message='')


class Count(AgentTask):
    """Counts to ud.n (one step per 20 ms); publishes feedback; preemptable."""
    INPUT_KEYS = ['n']

    def run(self, ud):
        for i in range(ud.n):
            self.check_preempt()
            self.feedback('COUNTING', f'{i}/{ud.n}')
            self.agent.backend.sleep(0.02)
        self.result['value'] = float(ud.n)
        self.result['message'] = f'counted to {ud.n}'
        return C.SUCCESS


class Fail(AgentTask):
    def run(self, ud):
        raise TaskError('it went wrong')


class Crash(AgentTask):
    def run(self, ud):
        return 1 / 0


class Parent(AgentTask):
    """Runs sub-task 'count' twice."""
    INPUT_KEYS = ['n']

    def run(self, ud):
        total = 0
        for _ in range(2):
            if self.call_task('count', {'n': ud.n}) != C.SUCCESS:
                raise TaskError('sub-task failed')
            total += self.last_sub_result['value']
        self.result['value'] = total
        return C.SUCCESS


class Strict(AgentTask):
    """Runs sub-task 'fail' as a step it cannot go on without."""

    def run(self, ud):
        self.call_task_or_raise('fail', {}, 'step 1')
        return C.SUCCESS


def gen_n(goal, agent):
    if not math.isfinite(goal.n) or goal.n < 0:
        raise ValueError(f'n must be a finite number >= 0, got {goal.n}')
    return {'n': int(goal.n)}


class SafeAgent(Agent):
    def __init__(self, backend):
        super().__init__('7', backend)
        self.safe_stops = 0

    def safe_stop(self):
        self.safe_stops += 1


@pytest.fixture
def agent():
    be = FakeBackend()
    a = SafeAgent(be)
    a.add_task('count', Count, object(), gen_n, Result, Feedback)
    a.add_task('fail', Fail, object(), lambda g, a: {}, Result, Feedback)
    a.add_task('crash', Crash, object(), lambda g, a: {}, Result, Feedback)
    a.add_task('parent', Parent, object(), gen_n, Result, Feedback)
    a.add_sub_task('count', 'parent', Count)
    a.add_task('strict', Strict, object(), lambda g, a: {}, Result, Feedback)
    a.add_sub_task('fail', 'strict', Fail)
    a.start()
    yield a
    be.shutdown = True
    a.shutdown()


def goal(n):
    return SimpleNamespace(n=n)


def test_state_machine_structure(agent):
    assert set(agent.sm.get_children()) == {C.DEFAULT_STATE, 'count', 'fail', 'crash', 'parent', 'strict'}


def test_task_succeeds_with_result_and_feedback(agent):
    s = agent.backend.servers['count_action']
    s.send(goal(3))
    assert s.wait() == 'succeeded'
    assert s.result.value == 3.0 and s.result.message == 'counted to 3'
    assert [f.message for f in s.feedback] == ['0/3', '1/3', '2/3']
    assert agent.running_task() == ''


def test_error_and_exception_abort_with_message_and_safe_stop(agent):
    f = agent.backend.servers['fail_action']
    f.send(goal(0))
    assert f.wait() == 'aborted' and f.result.message == 'it went wrong'
    c = agent.backend.servers['crash_action']
    c.send(goal(0))
    assert c.wait() == 'aborted' and 'ZeroDivisionError' in c.result.message
    assert agent.safe_stops == 2
    s = agent.backend.servers['count_action']         # the agent still works
    s.send(goal(1))
    assert s.wait() == 'succeeded'


def test_a_failed_sub_task_step_aborts_with_its_message(agent):
    s = agent.backend.servers['strict_action']
    s.send(goal(0))
    assert s.wait() == 'aborted' and s.result.message == 'step 1: it went wrong'


def test_bad_goal_aborted_with_message(agent):
    s = agent.backend.servers['count_action']
    s.send(goal(float('nan')))
    assert s.wait() == 'aborted' and 'bad goal' in s.result.message and 'finite' in s.result.message


def test_busy_agent_rejects_other_task(agent):
    s = agent.backend.servers['count_action']
    s.send(goal(50))
    agent.backend.clock.sleep(0.2)
    f = agent.backend.servers['fail_action']
    f.send(goal(0))
    assert f.wait() == 'aborted' and 'busy' in f.result.message and 'count' in f.result.message
    s.preempt = True
    assert s.wait() == 'preempted'


def test_preemption_stops_task_safely_and_agent_recovers(agent):
    s = agent.backend.servers['count_action']
    s.send(goal(500))
    agent.backend.clock.sleep(0.2)
    t0 = agent.backend.clock.now()
    s.preempt = True
    assert s.wait() == 'preempted'
    assert agent.backend.clock.now() - t0 < 1.0
    assert agent.safe_stops == 1
    s.send(goal(2))
    assert s.wait() == 'succeeded'


def test_sub_tasks_and_their_preemption(agent):
    p = agent.backend.servers['parent_action']
    p.send(goal(3))
    assert p.wait() == 'succeeded' and p.result.value == 6.0
    p.send(goal(500))
    agent.backend.clock.sleep(0.2)
    p.preempt = True
    assert p.wait() == 'preempted'


def test_agent_preempt_with_reason_aborts(agent):
    s = agent.backend.servers['count_action']
    s.send(goal(500))
    agent.backend.clock.sleep(0.2)
    assert agent.preempt_running('central unit heartbeat lost') == 'count'
    assert s.wait() == 'aborted' and 'heartbeat' in s.result.message


def test_not_accepting(agent):
    agent.accepting, agent.reject_reason = False, 'central unit heartbeat lost'
    s = agent.backend.servers['count_action']
    s.send(goal(1))
    assert s.wait() == 'aborted' and 'heartbeat' in s.result.message


def test_interface_dispatch_to_active_tasks_and_default_service():
    be = FakeBackend()
    iface = AgentInterface(be)
    got = []
    iface.add_subscriber('a', 'topic', str, lambda m: got.append(('a', m)))
    iface.add_subscriber('b', 'topic', str, lambda m: got.append(('b', m)))
    iface.add_subscriber(None, 'topic', str, lambda m: got.append(('always', m)))
    be.subs['topic']('m1')
    iface.push_active('a')
    be.subs['topic']('m2')
    iface.pop_active('a')
    assert got == [('always', 'm1'), ('always', 'm2'), ('a', 'm2')]
    iface.add_service_server('a', 'srv', object, lambda r: 'from a', default_callback=lambda r: 'default')
    assert be.services['srv']('req') == 'default'
    iface.push_active('a')
    assert be.services['srv']('req') == 'from a'
    with pytest.raises(TypeError):
        iface.add_subscriber('c', 'topic', int, print)


def test_a_closed_interface_drops_messages_until_opened():
    be = FakeBackend()
    iface = AgentInterface(be)
    got = []
    iface.add_subscriber(None, 'topic', str, got.append)
    iface.close()
    be.subs['topic']('early')
    iface.open()
    be.subs['topic']('late')
    assert got == ['late']


def test_an_agent_sees_no_message_before_it_is_started():
    """Realistic + GNSS-denied seed 101: a UAV's first ual/pose came while its constructor was still
    setting the attributes the pose callback uses; it failed, the home was never settled and every refill
    failed 'home unknown' for the rest of the trial."""
    from geometry_msgs.msg import PoseStamped
    from mbzirc_agents.uav_agent import UavAgent
    be = FakeBackend()
    agent = UavAgent('2', be, {})
    msg = PoseStamped()
    msg.header.frame_id = 'arena'
    msg.pose.orientation.w = 1.0
    be.subs['ual/pose'](msg)
    assert agent.pose is None and not be.errors
    agent.iface.open()
    be.subs['ual/pose'](msg)
    assert agent.pose is not None and not be.errors, be.errors


def test_bad_callback_is_logged_not_raised():
    be = FakeBackend()
    iface = AgentInterface(be)
    iface.add_subscriber(None, 't', str, lambda m: 1 / 0)
    be.subs['t']('x')
    assert be.errors and 'ZeroDivisionError' in be.errors[0]


def test_demand_subscribes_only_while_the_task_runs():
    """add_demand: the subscription that switches a lazy producer on exists only while its task runs."""
    made, dropped = [], []

    class Sub:
        def __init__(self, topic):
            self.topic = topic
            made.append(topic)

        def unregister(self):
            dropped.append(self.topic)

    be = FakeBackend()
    be.subscriber = lambda topic, msg_type, cb: Sub(topic)
    iface = AgentInterface(be)
    iface.add_demand('centre', 'circle_detection/middle_hole', object)
    assert made == [] and iface.demanded_topics() == []
    iface.push_active('other')
    assert made == []
    iface.push_active('centre')
    assert made == ['circle_detection/middle_hole']
    assert iface.demanded_topics() == ['circle_detection/middle_hole']
    iface.pop_active('centre')
    assert iface.demanded_topics() == []
    be.clock.sleep(0.1)                    # the demand is closed in a thread of its own
    assert dropped == ['circle_detection/middle_hole']
    iface.push_active('centre')            # a second run subscribes again
    assert made == ['circle_detection/middle_hole'] * 2


def test_a_demands_messages_go_to_its_callback_only_while_its_task_runs():
    """add_demand with a callback: a heavy topic one task reads is subscribed (and deserialised) only then; a
    callback that raises is logged, the subscriber goes on."""
    be = FakeBackend()
    iface = AgentInterface(be)
    got = []
    iface.add_demand('water', 'raw', object, lambda m: got.append(1 / m))
    assert 'raw' not in be.subs
    iface.push_active('water')
    be.subs['raw'](2)
    be.subs['raw'](0)                      # ZeroDivisionError: logged
    assert got == [0.5] and be.errors and 'ZeroDivisionError' in be.errors[-1]
    iface.pop_active('water')
    be.clock.sleep(0.1)                    # the demand is closed in a thread of its own
    assert 'raw' not in be.subs


def test_a_task_ends_even_when_closing_its_demand_hangs():
    """Unregistering tells the ROS master, which a robot whose link is cut cannot reach: the call hangs. The
    task must end all the same (a permanently cut UAV stayed in extinguish_facade_fire and never went home)."""
    import threading
    release = threading.Event()

    class HangingSub:
        def unregister(self):
            release.wait()                 # the master never answers (a real thread: not the sim clock's)

    be = FakeBackend()
    be.subscriber = lambda topic, msg_type, cb: HangingSub()
    be.start_thread = lambda name, target: threading.Thread(target=target, name=name, daemon=True).start()
    iface = AgentInterface(be)
    iface.add_demand('centre', 'circle_detection/middle_hole', object)
    iface.push_active('centre')
    done = threading.Event()
    threading.Thread(target=lambda: (iface.pop_active('centre'), done.set()), daemon=True).start()
    try:
        assert done.wait(2.0), 'pop_active waited for the master'
        assert iface.demanded_topics() == [] and 'centre' not in iface.active_tasks()
    finally:
        release.set()


def test_demand_that_cannot_subscribe_is_logged():
    be = FakeBackend()

    def boom(topic, msg_type, cb):
        raise RuntimeError('master unreachable')
    be.subscriber = boom
    iface = AgentInterface(be)
    iface.add_demand('centre', 'x', object)
    iface.push_active('centre')            # no exception: the task goes on without the producer
    iface.pop_active('centre')
    assert be.errors and 'master unreachable' in be.errors[-1]
