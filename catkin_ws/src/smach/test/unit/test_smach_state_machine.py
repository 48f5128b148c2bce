"""StateMachine: transitions, fall-through, nesting, add_auto, callbacks, consistency, construction."""
import threading

import pytest

import smach
from smach_test_helpers import Const


def make_counter_sm():
    @smach.cb_interface(outcomes=["again", "enough"], input_keys=["n"], output_keys=["n"])
    def inc(ud):
        ud.n = ud.n + 1
        return "again" if ud.n < 3 else "enough"

    sm = smach.StateMachine(outcomes=["finished"], input_keys=["n"], output_keys=["n"])
    with sm:
        smach.StateMachine.add("INC", smach.CBState(inc), transitions={"again": "INC", "enough": "finished"})
    return sm


def test_transitions_loop_and_finish_with_io_through_parent():
    sm = make_counter_sm()
    parent = smach.UserData()
    parent.n = 0
    assert sm.execute(parent) == "finished"
    assert parent.n == 3


def test_first_added_is_initial_and_set_initial_state():
    a, b = Const("x", outcomes=["x"]), Const("y", outcomes=["y"])
    sm = smach.StateMachine(outcomes=["x", "y"])
    with sm:
        smach.StateMachine.add("A", a)
        smach.StateMachine.add("B", b)
    assert sm.get_initial_states() == ["A"]
    assert sm.execute() == "x"
    ud = smach.UserData()
    ud.k = 1
    sm.set_initial_state(["B"], ud)
    assert sm.get_initial_states() == ["B"] and sm.userdata.k == 1
    assert sm.execute() == "y"
    with pytest.raises(smach.InvalidStateError):
        sm.set_initial_state(["A", "B"])
    sm.set_initial_state(["NOPE"])  # accepted (the state may be added later); refused when it runs
    with pytest.raises(smach.InvalidTransitionError, match="NOPE"):
        sm.execute()
    assert not sm.is_running()


def test_initial_state_and_userdata_set_before_the_state_is_added():
    # as upstream's monitor test: set_initial_state(['MON'], userdata=ud) on an empty machine
    ud = smach.UserData()
    ud.b = "B"
    sm = smach.StateMachine(outcomes=["x", "y"])
    sm.set_initial_state(["SECOND"], userdata=ud)
    assert sm.userdata.b == "B"
    copier = smach.CBState(lambda u: setattr(u, "a", u.b) or "y", outcomes=["y"], input_keys=["b"],
                           output_keys=["a"])
    with sm:
        smach.StateMachine.add("FIRST", Const("x", outcomes=["x"]))
        smach.StateMachine.add("SECOND", copier)
    assert sm.get_initial_states() == ["SECOND"]
    assert sm.execute() == "y" and sm.userdata.a == "B"


def test_outcome_without_transition_falls_through_to_container_outcome():
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("A", Const("done"))
    assert sm.execute() == "done"
    assert sm.get_internal_edges() == [["done", "A", None]]


def test_unbound_outcome_raises_at_runtime():
    sm = smach.StateMachine(outcomes=["other"])
    with sm:
        smach.StateMachine.add("A", Const("dangling"))
    with pytest.raises(smach.InvalidTransitionError):
        sm.execute()
    assert not sm.is_running()


def test_unregistered_returned_outcome_raises():
    class Liar(smach.State):
        def __init__(self):
            smach.State.__init__(self, outcomes=["a"])

        def execute(self, ud):
            return "b"

    sm = smach.StateMachine(outcomes=["a", "b"])
    with sm:
        smach.StateMachine.add("L", Liar())
    with pytest.raises(smach.InvalidTransitionError):
        sm.execute()


def test_user_exception_becomes_invalid_user_code_error():
    class Boom(smach.State):
        def __init__(self):
            smach.State.__init__(self, outcomes=["a"])

        def execute(self, ud):
            raise ValueError("boom")

    sm = smach.StateMachine(outcomes=["a"])
    with sm:
        smach.StateMachine.add("B", Boom())
    with pytest.raises(smach.InvalidUserCodeError, match="boom"):
        sm.execute()


def test_consistency_errors():
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("A", Const("done"), transitions={"done": "MISSING"})
    with pytest.raises(smach.InvalidTransitionError, match="MISSING"):
        sm.check_consistency()
    with pytest.raises(smach.InvalidTransitionError):
        sm.execute()
    empty = smach.StateMachine(outcomes=["done"])
    with pytest.raises(smach.InvalidTransitionError, match="No initial state"):
        empty.check_consistency()


def test_add_errors():
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("A", Const("done"))
        with pytest.raises(smach.InvalidStateError):
            smach.StateMachine.add("A", Const("done"))
        with pytest.raises(smach.InvalidStateError):
            smach.StateMachine.add("done", Const("done"))
        with pytest.raises(smach.InvalidTransitionError):
            smach.StateMachine.add("C", Const("done"), transitions={"nope": "A"})
        with pytest.raises(smach.InvalidStateError):
            smach.StateMachine.add("D", object())
    with pytest.raises(smach.InvalidConstructionError):
        smach.StateMachine.add("X", Const("done"))


def test_with_block_that_raises_closes_container_and_releases_lock():
    sm = smach.StateMachine(outcomes=["done"])
    with pytest.raises(RuntimeError):
        with sm:
            smach.StateMachine.add("A", Const("done"))
            raise RuntimeError("user error while building")
    assert not sm.is_opened()
    # the global construction lock must be free for another thread
    got = []

    def try_lock():
        ok = smach.Container._construction_lock.acquire(timeout=1.0)
        got.append(ok)
        if ok:
            smach.Container._construction_lock.release()

    t = threading.Thread(target=try_lock)
    t.start()
    t.join()
    assert got == [True]


def test_nested_state_machines_and_remapping():
    inner = smach.StateMachine(outcomes=["inner_done"], input_keys=["val"], output_keys=["res"])

    @smach.cb_interface(outcomes=["ok"], input_keys=["val"], output_keys=["res"])
    def double(ud):
        ud.res = ud.val * 2
        return "ok"

    with inner:
        smach.StateMachine.add("DOUBLE", smach.CBState(double), transitions={"ok": "inner_done"})
    outer = smach.StateMachine(outcomes=["end"])
    outer.userdata.x = 21
    with outer:
        smach.StateMachine.add("SUB", inner, transitions={"inner_done": "end"},
                               remapping={"val": "x", "res": "y"})
    assert outer.execute() == "end"
    assert outer.userdata.y == 42
    assert outer.get_children()["SUB"] is inner and outer["SUB"] is inner


def test_undeclared_key_in_state_raises():
    class Peek(smach.State):
        def __init__(self):
            smach.State.__init__(self, outcomes=["a"])

        def execute(self, ud):
            return ud.secret

    sm = smach.StateMachine(outcomes=["a"])
    sm.userdata.secret = "a"
    with sm:
        smach.StateMachine.add("P", Peek())
    with pytest.raises(smach.InvalidUserCodeError, match="declared as input"):
        sm.execute()


def test_add_auto_connects_to_next_state_unless_given():
    order = []

    def mk(name, outcomes, ret):
        return smach.CBState(lambda ud: (order.append(name), ret)[1], outcomes=outcomes)

    sm = smach.StateMachine(outcomes=["done", "failed"])
    with sm:
        smach.StateMachine.add_auto("A", mk("A", ["next", "fail"], "next"), ["next"], transitions={"fail": "failed"})
        smach.StateMachine.add_auto("B", mk("B", ["next"], "next"), ["next"])
        smach.StateMachine.add("C", mk("C", ["done"], "done"))
    assert sm.execute() == "done"
    assert order == ["A", "B", "C"]
    with pytest.raises(smach.InvalidStateError):
        with smach.StateMachine(outcomes=["x"]):
            smach.StateMachine.add_auto("A", Const("x"), ["nope"])


def test_callbacks_start_transition_termination_with_args():
    events = []
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("A", Const("go", outcomes=["go"]), transitions={"go": "B"})
        smach.StateMachine.add("B", Const("done"))
    sm.register_start_cb(lambda ud, init, tag: events.append(("start", tuple(init), tag)), ["s"])
    sm.register_transition_cb(lambda ud, active, tag: events.append(("trans", tuple(active), tag)), ["t"])
    sm.register_termination_cb(lambda ud, term, outcome, tag: events.append(("term", tuple(term), outcome, tag)),
                               ["e"])
    sm.execute()
    assert events == [("start", ("A",), "s"), ("trans", ("B",), "t"), ("term", ("B",), "done", "e")]


def test_failing_callback_is_logged_not_fatal(quiet_logs):
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("A", Const("done"))
    sm.register_start_cb(lambda ud, init: 1 / 0)
    assert sm.execute() == "done"
    assert any("start callback" in m for m in quiet_logs["error"])


def test_active_states_and_is_running_during_execution():
    seen = {}
    sm = smach.StateMachine(outcomes=["done"])

    def look(ud):
        seen["active"] = sm.get_active_states()
        seen["running"] = sm.is_running()
        return "done"

    with sm:
        smach.StateMachine.add("LOOK", smach.CBState(look, outcomes=["done"]))
    assert sm.get_active_states() == []
    sm.execute()
    assert seen == {"active": ["LOOK"], "running": True}
    assert not sm.is_running() and sm.get_active_states() == []


def test_shutdown_check_stops_loop():
    calls = {"n": 0}

    def loop(ud):
        calls["n"] += 1
        if calls["n"] == 3:
            smach.set_shutdown_check(lambda: True)
        return "again"

    sm = smach.StateMachine(outcomes=["never"])
    with sm:
        smach.StateMachine.add("L", smach.CBState(loop, outcomes=["again"]), transitions={"again": "L"})
    assert sm.execute() is None
    assert calls["n"] == 3


def test_sequence_connects_states_in_order():
    order = []
    seq = smach.Sequence(outcomes=["succeeded", "aborted"], connector_outcome="succeeded")
    with seq:
        for name in "ABC":
            smach.Sequence.add(name, smach.CBState(lambda ud, n=name: (order.append(n), "succeeded")[1],
                                                   outcomes=["succeeded", "aborted"]))
    assert seq.execute() == "succeeded"
    assert order == ["A", "B", "C"]
    assert ["succeeded", "A", "B"] in seq.get_internal_edges()


def test_sequence_abort_short_circuits():
    order = []
    seq = smach.Sequence(outcomes=["succeeded", "aborted"], connector_outcome="succeeded")
    with seq:
        smach.Sequence.add("A", smach.CBState(lambda ud: (order.append("A"), "aborted")[1],
                                              outcomes=["succeeded", "aborted"]))
        smach.Sequence.add("B", smach.CBState(lambda ud: (order.append("B"), "succeeded")[1],
                                              outcomes=["succeeded", "aborted"]))
    assert seq.execute() == "aborted"
    assert order == ["A"]
