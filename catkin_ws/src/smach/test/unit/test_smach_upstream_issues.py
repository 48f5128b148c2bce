"""Regression tests for preemption bugs reported against upstream executive_smach (ros/executive_smach#N).

Each interleaving is forced with events (no wall-clock sleeps): the timeouts only bound a failing run.
"""
import threading

import smach
from smach_test_helpers import Const

FAIL_AFTER_S = 5.0  # a run that gets here has lost a preempt


class Blocker(smach.State):
    """Blocks until preempted or released, with no polling.

    Preempted: services the request (unless ``service=False``) and returns 'preempted'; released:
    'done'. ``stopping`` is set once it saw a request; with ``hold=True`` it then waits for
    ``go`` before returning, which lets a test act between a state's service and its transition.
    """

    def __init__(self, service=True, hold=False):
        smach.State.__init__(self, outcomes=["done", "preempted"])
        self.service, self.hold = service, hold
        self.started, self.stopping, self.go = threading.Event(), threading.Event(), threading.Event()
        self._wake = threading.Event()
        self.saw_preempt_at_start = []  # one entry per run

    def request_preempt(self):
        smach.State.request_preempt(self)
        self._wake.set()

    def release(self):
        self._wake.set()

    def execute(self, ud):
        self.saw_preempt_at_start.append(self.preempt_requested())
        self.started.set()
        self._wake.wait(FAIL_AFTER_S)
        self._wake.clear()
        if not self.preempt_requested():
            return "done"
        if self.service:
            self.service_preempt()
        self.stopping.set()
        if self.hold:
            self.go.wait(FAIL_AFTER_S)
        return "preempted"


def run_async(container):
    box = {}
    thread = threading.Thread(target=lambda: box.setdefault("outcome", container.execute()), daemon=True)
    thread.start()
    return thread, box


def finish(thread, box):
    thread.join(2 * FAIL_AFTER_S)
    assert not thread.is_alive()
    return box["outcome"]


# ---- #53: a preempt that arrives when every child of a Concurrence has ended ---------------------------
def _concurrence_preempted_by_its_last_child(outcomes):
    """A Concurrence whose last child to end triggers its parent's preempt (from the termination cb, i.e.
    after the child ended and before the Concurrence returned): the moment of upstream's race."""
    holder = {}

    def preempt_parent_when_all_ended(child_outcomes):
        if all(o is not None for o in child_outcomes.values()):
            holder["parent"].request_preempt()
        return False

    cc = smach.Concurrence(outcomes=outcomes, default_outcome="done",
                           child_termination_cb=preempt_parent_when_all_ended)
    with cc:
        smach.Concurrence.add("ONLY", Const("done"))
    return cc, holder


def _sequence_of(cc, holder, nxt):
    """Sequence CC -> NEXT, which the Concurrence's last child preempts."""
    sq = smach.Sequence(outcomes=["done", "preempted"], connector_outcome="done")
    holder["parent"] = sq
    with sq:
        smach.Sequence.add("CC", cc)
        smach.Sequence.add("NEXT", nxt)
    return sq


def test_53_late_preempt_of_concurrence_reaches_the_next_state():
    """ros/executive_smach#53: the Concurrence claimed the preempt was serviced though no child saw it,
    so the next state of the sequence ran as if nothing happened."""
    cc, holder = _concurrence_preempted_by_its_last_child(["done"])  # it cannot say 'preempted'
    nxt = Blocker()
    sq = _sequence_of(cc, holder, nxt)
    assert sq.execute() == "preempted"
    assert nxt.saw_preempt_at_start == [True]
    assert not sq.preempt_requested() and not cc.preempt_requested()


def test_53_late_preempt_of_concurrence_with_a_preempted_outcome_returns_it():
    cc, holder = _concurrence_preempted_by_its_last_child(["done", "preempted"])
    nxt = Const("done")
    sq = _sequence_of(cc, holder, nxt)
    assert sq.execute() == "preempted"
    assert nxt.runs == 0
    assert not sq.preempt_requested() and not cc.preempt_requested()


# ---- #98: a Concurrence preempted while it terminates does not return 'preempted' ----------------------
def test_98_concurrence_preempted_while_terminating_returns_preempted():
    """ros/executive_smach#98: one child had ended (its outcome mapped) and the policy was preempting the
    other when the parent preempted the container: it returned the mapped outcome, and the parent went on
    as if the preempt had been serviced."""
    slow = Blocker()

    def first_end_stops_all(child_outcomes):
        if child_outcomes["FAST"] is not None:
            cc.request_preempt()  # the parent's preempt, at the very moment the container terminates
            return True
        return False

    cc = smach.Concurrence(outcomes=["succeeded", "preempted"], default_outcome="succeeded",
                           outcome_map={"succeeded": {"FAST": "succeeded"}},
                           child_termination_cb=first_end_stops_all)
    with cc:
        smach.Concurrence.add("FAST", Const("succeeded", outcomes=["succeeded", "preempted"]))
        smach.Concurrence.add("SLOW", slow)
    assert cc.execute() == "preempted"
    assert not cc.preempt_requested() and not slow.preempt_requested()


def test_98_concurrence_preempted_by_parent_overrides_outcome_map():
    a, b = Blocker(), Blocker()
    cc = smach.Concurrence(outcomes=["succeeded", "preempted"], default_outcome="succeeded",
                           outcome_map={"succeeded": {"A": "preempted"}})
    with cc:
        smach.Concurrence.add("A", a)
        smach.Concurrence.add("B", b)
    thread, box = run_async(cc)
    assert a.started.wait(FAIL_AFTER_S) and b.started.wait(FAIL_AFTER_S)
    cc.request_preempt()
    assert finish(thread, box) == "preempted"
    assert not cc.preempt_requested()


def test_98_policy_preemption_alone_keeps_the_outcome_map():
    # the container's own policy stopping a child is not a preempt of the container
    slow = Blocker()
    cc = smach.Concurrence(outcomes=["succeeded", "preempted"], default_outcome="preempted",
                           outcome_map={"succeeded": {"FAST": "succeeded", "SLOW": "preempted"}},
                           child_termination_cb=lambda outcomes: True)
    with cc:
        smach.Concurrence.add("FAST", Const("succeeded", outcomes=["succeeded"]))
        smach.Concurrence.add("SLOW", slow)
    assert cc.execute() == "succeeded"
    assert not cc.preempt_requested() and not slow.preempt_requested()


# ---- #88: a machine that cannot be preempted twice ------------------------------------------------------
def _a_b_c_machine(a, b):
    """A --preempted--> B --preempted--> C; B --done--> D (the shape of the report)."""
    c, d = Const("done"), Const("done")
    sm = smach.StateMachine(outcomes=["at_c", "at_d"])
    with sm:
        smach.StateMachine.add("A", a, transitions={"preempted": "B", "done": "D"})
        smach.StateMachine.add("B", b, transitions={"preempted": "C", "done": "D"})
        smach.StateMachine.add("C", c, transitions={"done": "at_c"})
        smach.StateMachine.add("D", d, transitions={"done": "at_d"})
    return sm, c, d


def test_88_machine_preempted_twice_in_a_row():
    """ros/executive_smach#88: after a preempt led A to B, a second preempt never reached B."""
    a, b = Blocker(), Blocker()
    sm, c, d = _a_b_c_machine(a, b)
    thread, box = run_async(sm)
    assert a.started.wait(FAIL_AFTER_S)
    sm.request_preempt()
    assert b.started.wait(FAIL_AFTER_S)
    assert b.saw_preempt_at_start == [False]  # the first preempt was serviced by A
    sm.request_preempt()
    assert finish(thread, box) == "at_c"
    assert (c.runs, d.runs) == (1, 0)
    assert not sm.preempt_requested()


def test_88_second_preempt_between_service_and_transition_reaches_next_state():
    # the second request arrives after A serviced the first one but before the machine left A
    a, b = Blocker(hold=True), Blocker()
    sm, c, d = _a_b_c_machine(a, b)
    thread, box = run_async(sm)
    assert a.started.wait(FAIL_AFTER_S)
    sm.request_preempt()
    assert a.stopping.wait(FAIL_AFTER_S)
    sm.request_preempt()
    a.go.set()
    assert finish(thread, box) == "at_c"
    assert b.saw_preempt_at_start == [True]
    assert not sm.preempt_requested() and not a.preempt_requested()


def test_88_state_looping_to_itself_is_preempted_every_time():
    retry = Blocker()
    calls = {"n": 0}

    def count_then_stop(ud):
        calls["n"] += 1
        return "again" if calls["n"] < 3 else "stop"

    sm = smach.StateMachine(outcomes=["stopped", "finished"])
    with sm:
        smach.StateMachine.add("WORK", retry, transitions={"preempted": "COUNT", "done": "finished"})
        smach.StateMachine.add("COUNT", smach.CBState(count_then_stop, outcomes=["again", "stop"]),
                               transitions={"again": "WORK", "stop": "stopped"})
    thread, box = run_async(sm)
    for run in range(3):
        assert retry.started.wait(FAIL_AFTER_S)
        retry.started.clear()
        sm.request_preempt()
    assert finish(thread, box) == "stopped"
    assert retry.saw_preempt_at_start == [False, False, False]


# ---- #37: a Concurrence ignores a preempt requested before it starts -----------------------------------
def test_37_preempt_passed_on_before_concurrence_starts_reaches_its_children():
    """ros/executive_smach#37: the previous state ignored the preempt, the machine passed it on to the
    Concurrence before it started, and the Concurrence ran its children as if nothing was requested."""
    ignoring = Blocker(service=False)
    child = Blocker()
    cc = smach.Concurrence(outcomes=["done", "preempted"], default_outcome="done")
    with cc:
        smach.Concurrence.add("CHILD", child)
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    with sm:
        smach.StateMachine.add("IGNORING", ignoring, transitions={"preempted": "CC", "done": "CC"})
        smach.StateMachine.add("CC", cc)
    thread, box = run_async(sm)
    assert ignoring.started.wait(FAIL_AFTER_S)
    sm.request_preempt()
    assert finish(thread, box) == "preempted"
    assert child.saw_preempt_at_start == [True]
    assert not sm.preempt_requested() and not cc.preempt_requested() and not ignoring.preempt_requested()


def test_37_preempt_before_a_lone_concurrence_executes():
    child = Blocker()
    cc = smach.Concurrence(outcomes=["done", "preempted"], default_outcome="done")
    with cc:
        smach.Concurrence.add("CHILD", child)
    cc.request_preempt()
    assert cc.execute() == "preempted"
    assert child.saw_preempt_at_start == [True]
    assert not cc.preempt_requested()
