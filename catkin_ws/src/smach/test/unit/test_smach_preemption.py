"""Preemption of a StateMachine at every point: before start, during a state, between states, nested,
ignored by a state, after the end, and repeated runs."""
import threading
import time

import smach
from smach_test_helpers import Const, Waiter


def run_in_thread(sm, ud=None):
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("outcome", sm.execute(ud)))
    t.start()
    return t, box


def two_state_sm(first, second=None):
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    with sm:
        smach.StateMachine.add("FIRST", first, transitions={"done": "SECOND" if second else "done"})
        if second:
            smach.StateMachine.add("SECOND", second)
    return sm


def test_preempt_during_state():
    w = Waiter()
    sm = two_state_sm(w, Const("done"))
    t, box = run_in_thread(sm)
    assert w.started.wait(2)
    sm.request_preempt()
    t.join(3)
    assert box["outcome"] == "preempted"
    assert not sm.preempt_requested() and not w.preempt_requested()


def test_preempt_before_start_is_seen_by_first_state():
    w = Waiter(timeout=2)
    sm = two_state_sm(w)
    sm.request_preempt()
    assert sm.execute() == "preempted"
    assert w.saw_preempt_at_start is True
    assert not sm.preempt_requested()


def test_preempt_between_states_reaches_next_state():
    second = Waiter(timeout=2)
    first = Const("done", outcomes=["done", "preempted"])
    sm = two_state_sm(first, second)
    # the transition callback runs between FIRST and SECOND (with the transition lock held)
    sm.register_transition_cb(lambda ud, active: sm.request_preempt())
    assert sm.execute() == "preempted"
    assert second.saw_preempt_at_start is True
    assert not sm.preempt_requested()


def test_ignored_preempt_propagates_to_next_state_then_serviced():
    ignoring = Waiter(timeout=2, service=False)
    second = Waiter(timeout=2)
    sm = two_state_sm(ignoring, second)
    t, box = run_in_thread(sm)
    assert ignoring.started.wait(2)
    sm.request_preempt()
    t.join(5)
    assert box["outcome"] == "preempted"
    assert second.saw_preempt_at_start is True
    assert not ignoring.preempt_requested()  # recalled when the next state was preempted


def test_unserviced_preempt_at_end_stays_requested_and_child_is_recalled():
    ignoring = Waiter(timeout=2, service=False)
    sm = two_state_sm(ignoring)
    t, box = run_in_thread(sm)
    assert ignoring.started.wait(2)
    sm.request_preempt()
    t.join(3)
    assert box["outcome"] == "done"
    assert sm.preempt_requested()  # nobody serviced it: the parent must know (upstream semantics)
    assert not ignoring.preempt_requested()
    sm.recall_preempt()
    assert not sm.preempt_requested()


def test_nested_preempt_reaches_innermost_state():
    w = Waiter()
    inner = smach.StateMachine(outcomes=["done", "preempted"])
    with inner:
        smach.StateMachine.add("W", w)
    outer = smach.StateMachine(outcomes=["done", "preempted"])
    with outer:
        smach.StateMachine.add("INNER", inner)
    t, box = run_in_thread(outer)
    assert w.started.wait(2)
    outer.request_preempt()
    t.join(3)
    assert box["outcome"] == "preempted"
    assert not outer.preempt_requested() and not inner.preempt_requested()


def test_machine_is_reusable_after_preemption():
    w = Waiter(timeout=0.2)
    sm = two_state_sm(w)
    t, box = run_in_thread(sm)
    assert w.started.wait(2)
    sm.request_preempt()
    t.join(3)
    assert box["outcome"] == "preempted"
    w.started.clear()
    assert sm.execute() == "done"  # runs to the end without a stale preempt


def test_preempt_storm_never_deadlocks_or_loses_outcome():
    for _ in range(20):
        w = Waiter(timeout=1)
        sm = two_state_sm(Const("done", outcomes=["done", "preempted"]), w)
        t, box = run_in_thread(sm)
        for _ in range(5):
            sm.request_preempt()
            time.sleep(0.001)
        t.join(3)
        assert not t.is_alive()
        assert box["outcome"] in ("done", "preempted")
