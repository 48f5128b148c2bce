"""Concurrence: outcome policies, child termination, preemption and its races, userdata, errors."""
import threading
import time

import pytest

import smach
from smach_test_helpers import Const, Waiter


class Sleeper(smach.State):
    def __init__(self, delay, outcome="done", key=None):
        smach.State.__init__(self, outcomes=["done", "other", "preempted"], output_keys=[key] if key else [])
        self.delay, self.outcome, self.key = delay, outcome, key

    def execute(self, ud):
        time.sleep(self.delay)
        if self.key:
            setattr(ud, self.key, self.delay)
        return self.outcome


def make_cc(children, **kw):
    kw.setdefault("default_outcome", "default")
    cc = smach.Concurrence(outcomes=["default", "mapped", "both", "cb", "preempted"], **kw)
    with cc:
        for label, st in children.items():
            smach.Concurrence.add(label, st)
    return cc


def test_children_run_concurrently():
    # each child waits until the other one has started: only possible if they run at the same time
    started = {"A": threading.Event(), "B": threading.Event()}

    def both(ud, me, other):
        started[me].set()
        return "done" if started[other].wait(5) else "other"

    cc = make_cc({"A": smach.CBState(both, ["A", "B"], outcomes=["done", "other"]),
                  "B": smach.CBState(both, ["B", "A"], outcomes=["done", "other"])},
                 outcome_map={"both": {"A": "done", "B": "done"}})
    assert cc.execute() == "both"


def test_outcome_map_most_specific_entry_wins():
    cc = make_cc({"A": Sleeper(0.01), "B": Sleeper(0.01, "other")},
                 outcome_map={"mapped": {"A": "done"}, "both": {"A": "done", "B": "other"}})
    assert cc.execute() == "both"
    cc2 = make_cc({"A": Sleeper(0.01), "B": Sleeper(0.01, "done")},
                  outcome_map={"mapped": {"A": "done"}, "both": {"A": "done", "B": "other"}})
    assert cc2.execute() == "mapped"


def test_outcome_cb_overrides_map_and_none_keeps_it():
    seen = []
    cc = make_cc({"A": Sleeper(0.01)}, outcome_map={"mapped": {"A": "done"}},
                 outcome_cb=lambda outcomes: (seen.append(dict(outcomes)), "cb")[1])
    assert cc.execute() == "cb"
    assert seen == [{"A": "done"}]
    cc2 = make_cc({"A": Sleeper(0.01)}, outcome_map={"mapped": {"A": "done"}}, outcome_cb=lambda o: None)
    assert cc2.execute() == "mapped"


def test_unregistered_outcome_from_cb_raises():
    cc = make_cc({"A": Sleeper(0.01)}, outcome_cb=lambda o: "bogus")
    with pytest.raises(smach.InvalidTransitionError):
        cc.execute()


def test_child_termination_cb_preempts_the_rest():
    w = Waiter(timeout=5)
    calls = []

    def term_cb(outcomes):
        calls.append(dict(outcomes))
        return outcomes.get("FAST") == "done"

    cc = make_cc({"FAST": Sleeper(0.05), "SLOW": w}, child_termination_cb=term_cb,
                 outcome_map={"mapped": {"FAST": "done", "SLOW": "preempted"}})
    t0 = time.monotonic()
    assert cc.execute() == "mapped"
    assert time.monotonic() - t0 < 3.0  # SLOW alone would take 5 s
    assert calls[0] == {"FAST": "done", "SLOW": None}
    assert not w.preempt_requested()


def test_without_termination_cb_waits_for_all():
    cc = make_cc({"A": Sleeper(0.01), "B": Sleeper(0.3)})
    t0 = time.monotonic()
    cc.execute()
    assert time.monotonic() - t0 >= 0.29


def test_preempt_container_preempts_children_and_is_serviced():
    a, b = Waiter(), Waiter()
    cc = make_cc({"A": a, "B": b}, outcome_map={"preempted": {"A": "preempted", "B": "preempted"}})
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("o", cc.execute()))
    t.start()
    assert a.started.wait(2) and b.started.wait(2)
    cc.request_preempt()
    t.join(3)
    assert box["o"] == "preempted"
    assert not cc.preempt_requested()


def test_preempt_race_with_children_finishing_at_same_moment():
    # children end exactly when the preempt arrives: never hangs, never returns an unregistered outcome
    for i in range(30):
        cc = make_cc({"A": Sleeper(0.01), "B": Sleeper(0.01)})
        box = {}
        t = threading.Thread(target=lambda: box.setdefault("o", cc.execute()))
        t.start()
        time.sleep(0.01 + (i % 3) * 0.001)
        cc.request_preempt()
        t.join(3)
        assert not t.is_alive()
        assert box["o"] in cc.get_registered_outcomes()


def test_unserviced_preempt_is_recalled_on_children():
    # a container with no 'preempted' outcome cannot honour the preempt itself: it stays requested
    ignoring = Waiter(timeout=0.2, service=False)
    cc = smach.Concurrence(outcomes=["default"], default_outcome="default")
    with cc:
        smach.Concurrence.add("A", ignoring)
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("o", cc.execute()))
    t.start()
    assert ignoring.started.wait(2)
    cc.request_preempt()
    t.join(3)
    assert box["o"] == "default"
    assert not ignoring.preempt_requested()
    assert cc.preempt_requested()  # not serviced by its children


def test_child_exception_raises_in_parent():
    class Boom(smach.State):
        def __init__(self):
            smach.State.__init__(self, outcomes=["done"])

        def execute(self, ud):
            raise RuntimeError("kaboom")

    cc = make_cc({"A": Boom(), "B": Waiter(timeout=10)})
    t0 = time.monotonic()
    with pytest.raises(smach.InvalidUserCodeError, match="kaboom"):
        cc.execute()
    assert time.monotonic() - t0 < 5.0  # the other child was preempted, not waited for


def test_userdata_in_and_out_with_remapping():
    cc = smach.Concurrence(outcomes=["done"], default_outcome="done", input_keys=["x"], output_keys=["a_out"])

    @smach.cb_interface(outcomes=["done"], input_keys=["inp"], output_keys=["out"])
    def cb(ud):
        ud.out = ud.inp + 1
        return "done"

    with cc:
        smach.Concurrence.add("A", smach.CBState(cb), remapping={"inp": "x", "out": "a_out"})
    parent = smach.UserData()
    parent.x = 1
    assert cc.execute(parent) == "done"
    assert parent.a_out == 2


def test_empty_concurrence_raises_instead_of_hanging():
    # upstream's concurrence test: a Concurrence with no child raises InvalidStateError when executed
    cc = smach.Concurrence(outcomes=["done"], default_outcome="done")
    with pytest.raises(smach.InvalidStateError, match="no child"):
        cc.execute()
    assert not cc.is_running()


def test_policy_validation_and_consistency():
    with pytest.raises(smach.InvalidStateError):
        smach.Concurrence(outcomes=["a"], default_outcome="b")
    with pytest.raises(smach.InvalidStateError):
        smach.Concurrence(outcomes=["a"], default_outcome="a", outcome_map={"zz": {}})
    with pytest.raises(smach.InvalidStateError):
        smach.Concurrence(outcomes=["a"], default_outcome="a", outcome_cb="notcallable")
    cc = smach.Concurrence(outcomes=["a"], default_outcome="a", outcome_map={"a": {"GHOST": "x"}})
    with cc:
        smach.Concurrence.add("A", Const("x"))
    with pytest.raises(smach.InvalidTransitionError, match="GHOST"):
        cc.execute()


def test_structure_queries_and_callbacks():
    events = []
    cc = make_cc({"A": Sleeper(0.05), "B": Sleeper(0.1)}, outcome_map={"mapped": {"A": "done"}})
    cc.register_transition_cb(lambda ud, active: events.append(tuple(sorted(active))))
    cc.register_termination_cb(lambda ud, term, outcome: events.append(("end", outcome)))
    assert set(cc.get_initial_states()) == {"A", "B"}
    assert cc.get_internal_edges() == [["done", "A", "mapped"]]
    cc.execute()
    assert ("B",) in events and events[-1] == ("end", "mapped")
    assert cc.get_active_states() == []


def test_nested_concurrence_in_state_machine_preempts():
    w1, w2 = Waiter(), Waiter()
    cc = smach.Concurrence(outcomes=["done", "preempted"], default_outcome="done",
                           outcome_map={"preempted": {"A": "preempted", "B": "preempted"}})
    with cc:
        smach.Concurrence.add("A", w1)
        smach.Concurrence.add("B", w2)
    sm = smach.StateMachine(outcomes=["done", "preempted"])
    with sm:
        smach.StateMachine.add("CC", cc)
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("o", sm.execute()))
    t.start()
    assert w1.started.wait(2) and w2.started.wait(2)
    sm.request_preempt()
    t.join(3)
    assert box["o"] == "preempted"
    assert not sm.preempt_requested()
