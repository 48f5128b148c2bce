"""Iterator: loops, breaks, exhaustion, final outcome map, callables, preemption, consistency."""
import threading

import pytest

import smach
from smach_test_helpers import Waiter


def collector(outcome_for=lambda item: "continue"):
    @smach.cb_interface(outcomes=["continue", "stop", "failed"], input_keys=["item", "acc"], output_keys=["acc"])
    def cb(ud):
        ud.acc = ud.acc + [ud.item]
        return outcome_for(ud.item)
    return smach.CBState(cb)


def make_it(items, outcome_for=lambda i: "continue", **kw):
    it = smach.Iterator(outcomes=["succeeded", "stopped", "aborted", "preempted"], input_keys=["acc"],
                        output_keys=["acc"], it=items, it_label="item", exhausted_outcome="succeeded")
    with it:
        smach.Iterator.set_contained_state("BODY", collector(outcome_for), loop_outcomes=["continue"], **kw)
    return it


def test_iterates_all_items_then_exhausted():
    it = make_it([1, 2, 3], final_outcome_map={"stop": "stopped", "failed": "aborted"})
    ud = smach.UserData()
    ud.acc = []
    assert it.execute(ud) == "succeeded"
    assert ud.acc == [1, 2, 3]


def test_break_outcome_stops_and_is_mapped():
    it = make_it(range(10), lambda i: "stop" if i == 2 else "continue", break_outcomes=["stop"],
                 final_outcome_map={"stop": "stopped", "failed": "aborted"})
    ud = smach.UserData()
    ud.acc = []
    assert it.execute(ud) == "stopped"
    assert ud.acc == [0, 1, 2]


def test_non_loop_outcome_also_stops():
    it = make_it(range(5), lambda i: "failed" if i == 1 else "continue",
                 final_outcome_map={"stop": "stopped", "failed": "aborted"})
    ud = smach.UserData()
    ud.acc = []
    assert it.execute(ud) == "aborted"
    assert ud.acc == [0, 1]


def test_unmapped_unregistered_stop_outcome_raises():
    it = make_it([1], lambda i: "failed")
    ud = smach.UserData()
    ud.acc = []
    with pytest.raises(smach.InvalidTransitionError):
        it.execute(ud)


def test_callable_items_evaluated_at_start_and_set_iteritems():
    src = {"n": 2}
    it = make_it(lambda: range(src["n"]))
    src["n"] = 4
    ud = smach.UserData()
    ud.acc = []
    it.execute(ud)
    assert ud.acc == [0, 1, 2, 3]
    it.set_iteritems(["a"], "item")
    ud.acc = []
    it.execute(ud)
    assert ud.acc == ["a"]


def test_empty_iterable_gives_exhausted():
    it = make_it([])
    ud = smach.UserData()
    ud.acc = []
    assert it.execute(ud) == "succeeded"


def test_preempt_during_item_returns_preempted():
    w = Waiter(timeout=5)
    it = smach.Iterator(outcomes=["succeeded", "preempted"], input_keys=[], output_keys=[], it=range(100),
                        exhausted_outcome="succeeded")
    with it:
        smach.Iterator.set_contained_state("W", w, loop_outcomes=["done"])
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("o", it.execute(smach.UserData())))
    t.start()
    assert w.started.wait(2)
    it.request_preempt()
    t.join(3)
    assert box["o"] == "preempted"
    assert not it.preempt_requested() and not w.preempt_requested()


def test_preempt_between_items_never_returns_loop_outcome():
    it = make_it(range(1000))
    it.register_transition_cb(lambda ud, active: it.request_preempt() if len(ud.acc) == 3 else None)
    ud = smach.UserData()
    ud.acc = []
    assert it.execute(ud) == "preempted"
    assert ud.acc == [0, 1, 2]


def test_structure_and_consistency():
    it = make_it([1], break_outcomes=["stop"], final_outcome_map={"stop": "stopped", "failed": "aborted"})
    assert it.get_children().keys() == {"BODY"}
    assert it.get_initial_states() == ["BODY"]
    assert ["continue", "BODY", "BODY"] in it.get_internal_edges()
    assert ["stop", "BODY", "stopped"] in it.get_internal_edges()
    bad = smach.Iterator(outcomes=["x"], input_keys=[], output_keys=[], it=[1])
    with pytest.raises(smach.InvalidStateError):
        bad.execute(smach.UserData())
    with bad:
        smach.Iterator.set_contained_state("B", collector(), loop_outcomes=["continue"])
    with pytest.raises(smach.InvalidTransitionError, match="exhausted"):
        bad.execute(smach.UserData())
    with pytest.raises(smach.InvalidTransitionError):
        with make_it([1]):
            smach.Iterator.set_contained_state("B", collector(), loop_outcomes=["nope"])


def test_iterator_inside_state_machine_tutorial_style():
    sm = smach.StateMachine(outcomes=["succeeded", "aborted", "preempted"])
    sm.userdata.nums = list(range(6))
    sm.userdata.even_nums = []
    sm.userdata.odd_nums = []
    with sm:
        it = smach.Iterator(outcomes=["succeeded", "preempted", "aborted"],
                            input_keys=["nums", "even_nums", "odd_nums"], output_keys=["even_nums", "odd_nums"],
                            it=lambda: range(0, len(sm.userdata.nums)), it_label="index",
                            exhausted_outcome="succeeded")
        with it:
            body = smach.StateMachine(outcomes=["succeeded", "preempted", "aborted", "continue"],
                                      input_keys=["nums", "index", "even_nums", "odd_nums"],
                                      output_keys=["even_nums", "odd_nums"])
            with body:
                @smach.cb_interface(input_keys=["nums", "index", "even_nums", "odd_nums"],
                                    output_keys=["odd_nums", "even_nums"], outcomes=["even", "odd"])
                def even_odd_cb(ud):
                    if ud.nums[ud.index] % 2 == 0:
                        ud.even_nums.append(ud.nums[ud.index])
                        return "even"
                    ud.odd_nums.append(ud.nums[ud.index])
                    return "odd"
                smach.StateMachine.add("EVEN_OR_ODD", smach.CBState(even_odd_cb),
                                       {"even": "continue", "odd": "continue"})
            smach.Iterator.set_contained_state("CONTAINER_STATE", body, loop_outcomes=["continue"])
        smach.StateMachine.add("TUTORIAL_IT", it, {"succeeded": "succeeded", "aborted": "aborted"})
    assert sm.execute() == "succeeded"
    assert sm.userdata.even_nums == [0, 2, 4] and sm.userdata.odd_nums == [1, 3, 5]
