"""The scenarios of executive_smach's own container rostests (state_machine, sequence, concurrence), told
again without ROS, so that compatibility with programs written for the original is held here.

The states that need ROS there (ConditionState, SimpleActionState) are replaced by plain ones; the ROS
parts are in smach_ros/test/test_upstream_scenarios.py.
"""
import threading

import pytest

import smach
from smach_test_helpers import Const

WAIT_S = 5.0  # bounds a failing run only


class WriteA(smach.State):
    """Writes 'A' to key 'a' and tells anyone waiting for it."""

    def __init__(self, written=None):
        smach.State.__init__(self, outcomes=["done"], output_keys=["a"])
        self.written = written or threading.Event()

    def execute(self, ud):
        ud.a = "A"
        self.written.set()
        return "done"


class CopyAToB(smach.State):
    """Copies key 'a' to key 'b' (after ``written`` when given: the writer may run concurrently);
    returns 'preempted' if a preempt came meanwhile (without servicing it, like upstream's Getter)."""

    def __init__(self, written=None, linger=None):
        smach.State.__init__(self, outcomes=["done", "preempted"], input_keys=["a"], output_keys=["b"])
        self.written, self.linger = written, linger

    def execute(self, ud):
        if self.written is not None:
            assert self.written.wait(WAIT_S)
        ud.b = ud.a
        if self.linger is not None:
            self.linger.wait(WAIT_S)  # set by request_preempt: stands in for upstream's 1 s of work
        return "preempted" if self.preempt_requested() else "done"

    def request_preempt(self):
        smach.State.request_preempt(self)
        if self.linger is not None:
            self.linger.set()


def machine_that_needs(key):
    """A nested machine with input key ``key`` whose only state checks it can read it ('done'), else
    'aborted' (upstream's ConditionState asserter)."""
    inner = smach.StateMachine(outcomes=["done", "aborted"])
    inner.register_input_keys([key])
    with inner:
        smach.StateMachine.add("ASSERTER", smach.CBState(lambda ud: "true" if key in ud else "false",
                                                         outcomes=["true", "false"], input_keys=[key]),
                               {"true": "done", "false": "aborted"})
    return inner


# ---- state_machine ---------------------------------------------------------------------------------------
def test_userdata_flows_from_one_state_to_the_next():
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("SETTER", WriteA(), {"done": "GETTER"})
        smach.StateMachine.add("GETTER", CopyAToB(), {})
    assert sm.execute() == "done"
    assert (sm.userdata.a, sm.userdata.b) == ("A", "A")


def test_nested_machine_reads_its_input_keys_from_the_parent():
    sm = smach.StateMachine(outcomes=["done", "aborted"])
    with sm:
        smach.StateMachine.add("SETTER", WriteA(), {"done": "GETTER"})
        smach.StateMachine.add("GETTER", CopyAToB(), {"done": "NEST"})
        smach.StateMachine.add("NEST", machine_that_needs("a"))
    assert sm.execute() == "done"
    assert (sm.userdata.a, sm.userdata.b) == ("A", "A")


def test_userdata_set_on_the_machine_before_it_runs_reaches_nested_machines():
    sm = smach.StateMachine(outcomes=["done", "aborted"])
    sm.userdata.foo = 1
    with sm:
        smach.StateMachine.add("SETTER", WriteA(), {"done": "NEST"})
        smach.StateMachine.add("NEST", machine_that_needs("foo"))
    assert sm.execute() == "done"
    assert sm.userdata.foo == 1


def test_remapping_renames_keys_for_each_state():
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("SETTER", WriteA(), {"done": "GETTER"}, remapping={"a": "x"})
        smach.StateMachine.add("GETTER", CopyAToB(), {"done": "done"}, remapping={"a": "x", "b": "y"})
    assert sm.execute() == "done"
    assert (sm.userdata.x, sm.userdata.y) == ("A", "A")
    assert "a" not in sm.userdata and "b" not in sm.userdata


def test_add_auto_chains_states_on_their_connector_outcomes():
    sm = smach.StateMachine(outcomes=["succeeded", "aborted", "done"])
    ok = lambda: Const("succeeded", outcomes=["succeeded", "aborted"])  # noqa: E731
    first, second, third = ok(), ok(), ok()
    with sm:
        smach.StateMachine.add_auto("FIRST", first, ["succeeded"])
        smach.StateMachine.add_auto("SECOND", second, ["succeeded"])
        smach.StateMachine.add("THIRD", third, {"succeeded": "done"})
    assert sm.execute() == "done"
    assert (first.runs, second.runs, third.runs) == (1, 1, 1)


def test_nested_with_blocks_on_the_same_machine_share_transitions():
    # upstream's 'group' test: states added in an inner ``with`` share a transitions dict; here SECOND
    # aborts and the shared transition leads to FAILSAUCE
    sm = smach.StateMachine(outcomes=["succeeded", "done"])
    failsauce = Const("done")
    with sm:
        smach.StateMachine.add("FAILSAUCE", failsauce)
        group = {"aborted": "FAILSAUCE"}
        with sm:
            smach.StateMachine.add("FIRST", Const("succeeded", outcomes=["succeeded", "aborted"]),
                                   dict(group, succeeded="SECOND"))
            smach.StateMachine.add("SECOND", Const("aborted", outcomes=["succeeded", "aborted"]), group)
    assert sm.get_initial_states() == ["FAILSAUCE"]  # the first added
    assert sm.execute() == "done" and failsauce.runs == 1
    sm.set_initial_state(["FIRST"])
    assert sm.execute() == "done" and failsauce.runs == 2


def test_opened_and_add_on_the_instance():
    sm = smach.StateMachine(outcomes=["succeeded", "aborted"])
    with sm.opened():
        sm.add("FIRST", Const("succeeded", outcomes=["succeeded", "aborted"]), {})
        sm.add("SECOND", Const("aborted", outcomes=["succeeded", "aborted"]), {})
    assert sm.execute() == "succeeded"  # FIRST's outcome falls through as the machine's


def raises_in_execute():
    def boom(ud):
        raise RuntimeError("Test exception")
    return smach.CBState(boom, outcomes=["done"])


def test_exception_in_a_state_raises_and_lowers_is_running():
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("ERROR", raises_in_execute())
    with pytest.raises(smach.InvalidUserCodeError, match="Test exception"):
        sm.execute()
    assert sm.is_running() is False


# ---- sequence --------------------------------------------------------------------------------------------
def test_sequence_connects_states_and_an_explicit_transition_ends_it():
    sq = smach.Sequence(outcomes=["succeeded", "aborted", "done"], connector_outcome="succeeded")
    steps = [Const("succeeded", outcomes=["succeeded", "aborted"]) for _ in range(3)]
    with sq:
        smach.Sequence.add("FIRST", steps[0])
        smach.Sequence.add("SECOND", steps[1])
        smach.Sequence.add("THIRD", steps[2], {"succeeded": "done"})
    assert sq.execute() == "done"
    assert [s.runs for s in steps] == [1, 1, 1]


def test_exception_in_a_sequence_stops_it_before_the_next_state():
    sq = smach.Sequence(outcomes=["done"], connector_outcome="done")
    with sq:
        smach.Sequence.add("OK", Const("done"))
        smach.Sequence.add("ERROR", raises_in_execute())
        smach.Sequence.add("IGNORED", WriteA())
    with pytest.raises(smach.InvalidUserCodeError):
        sq.execute()
    assert sq.is_running() is False
    assert "a" not in sq.userdata


# ---- concurrence -----------------------------------------------------------------------------------------
def setter_and_getter(cc, linger=None):
    written = threading.Event()
    with cc:
        smach.Concurrence.add("SETTER", WriteA(written))
        smach.Concurrence.add("GETTER", CopyAToB(written, linger))


def assert_a_and_b_copied(cc):
    assert (cc.userdata.a, cc.userdata.b) == ("A", "A")


def test_concurrence_in_a_machine_maps_one_child_outcome():
    sm = smach.StateMachine(outcomes=["done", "succeeded"])
    with sm:
        cc = smach.Concurrence(["succeeded", "done"], default_outcome="done",
                               outcome_map={"succeeded": {"SETTER": "done"}})
        sm.add("CONCURRENT", cc)
        setter_and_getter(cc)
    assert sm.execute() == "succeeded"
    assert_a_and_b_copied(cc)


def test_concurrence_first_child_to_end_preempts_its_sibling():
    cc = smach.Concurrence(["succeeded", "done"], default_outcome="done", child_termination_cb=lambda so: True,
                           outcome_map={"succeeded": {"SETTER": "done", "GETTER": "preempted"}})
    setter_and_getter(cc, linger=threading.Event())
    assert cc.execute() == "succeeded"
    assert_a_and_b_copied(cc)


def test_concurrence_waits_for_every_child_without_termination_cb_verdict():
    cc = smach.Concurrence(["succeeded", "done"], default_outcome="done", child_termination_cb=lambda so: False,
                           outcome_map={"succeeded": {"SETTER": "done", "GETTER": "done"}})
    setter_and_getter(cc)
    assert cc.execute() == "succeeded"
    assert_a_and_b_copied(cc)


def test_concurrence_outcome_cb_gets_every_child_outcome():
    seen = []

    def outcome_cb(child_outcomes):
        seen.append(dict(child_outcomes))
        return list(set(child_outcomes.values()))[0]

    cc = smach.Concurrence(["succeeded", "done"], default_outcome="succeeded",
                           child_termination_cb=lambda so: False, outcome_cb=outcome_cb)
    setter_and_getter(cc)
    assert cc.execute() == "done"
    assert seen == [{"SETTER": "done", "GETTER": "done"}]
    assert_a_and_b_copied(cc)
