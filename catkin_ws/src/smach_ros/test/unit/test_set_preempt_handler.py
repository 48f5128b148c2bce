"""smach_ros.set_preempt_handler: a container is preempted when the node shuts down (no master needed)."""
import rospy
import smach

import smach_ros


class Waiting(smach.State):
    def __init__(self):
        super().__init__(outcomes=['done', 'preempted'])

    def execute(self, ud):
        return 'preempted' if self.preempt_requested() else 'done'


def test_shutdown_hook_requests_preempt(monkeypatch):
    hooks = []
    monkeypatch.setattr(rospy.core, 'add_preshutdown_hook', hooks.append, raising=False)
    sm = smach.StateMachine(outcomes=['done', 'preempted'])
    with sm:
        smach.StateMachine.add('WAIT', Waiting(), transitions={'done': 'done', 'preempted': 'preempted'})
    smach_ros.set_preempt_handler(sm)
    assert len(hooks) == 1 and not sm.preempt_requested()
    hooks[0]('shutdown requested')
    assert sm.preempt_requested()


def test_falls_back_to_on_shutdown(monkeypatch):
    registered = []
    monkeypatch.delattr(rospy.core, 'add_preshutdown_hook', raising=False)
    monkeypatch.setattr(rospy, 'on_shutdown', registered.append)
    state = Waiting()
    smach_ros.set_preempt_handler(state)
    assert len(registered) == 1
    registered[0]()
    assert state.preempt_requested()
