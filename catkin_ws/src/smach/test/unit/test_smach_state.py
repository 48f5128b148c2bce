"""State, CBState, cb_interface and the interface helpers."""
import pytest

import smach


def test_state_registers_interface_in_order_without_duplicates():
    s = smach.State(outcomes=["a", "b", "a"], input_keys=["x"], output_keys=["y"], io_keys=["z"])
    assert s.get_registered_outcomes() == ("a", "b")
    assert set(s.get_registered_input_keys()) == {"x", "z"}
    assert set(s.get_registered_output_keys()) == {"y", "z"}
    s.register_outcomes(["c"])
    s.register_input_keys(["w"])
    s.register_output_keys(["v"])
    s.register_io_keys(["u"])
    assert "c" in s.get_registered_outcomes()
    assert {"w", "u"} <= set(s.get_registered_input_keys())
    assert {"v", "u"} <= set(s.get_registered_output_keys())


def test_state_execute_is_abstract():
    with pytest.raises(NotImplementedError):
        smach.State(outcomes=["a"]).execute(smach.UserData())


def test_preempt_flag_request_service_recall():
    s = smach.State(outcomes=["a"])
    assert not s.preempt_requested()
    s.request_preempt()
    assert s.preempt_requested()
    s.service_preempt()
    assert not s.preempt_requested()
    s.request_preempt()
    s.recall_preempt()
    assert not s.preempt_requested()


def test_cbstate_passes_args_and_kwargs():
    seen = []

    def cb(ud, a, b=None):
        seen.append((ud.x, a, b))
        return "ok"

    st = smach.CBState(cb, cb_args=[1], cb_kwargs={"b": 2}, outcomes=["ok"], input_keys=["x"])
    ud = smach.UserData()
    ud.x = 5
    assert st.execute(smach.Remapper(ud, ["x"], [], {})) == "ok"
    assert seen == [(5, 1, 2)]


def test_cb_interface_registers_keys_including_io_keys():
    @smach.cb_interface(outcomes=["done"], input_keys=["a"], output_keys=["b"], io_keys=["c"])
    def cb(ud):
        ud.b = ud.a + ud.c
        ud.c = 0
        return "done"

    assert smach.has_smach_interface(cb)
    st = smach.CBState(cb)
    assert st.get_registered_outcomes() == ("done",)
    assert set(st.get_registered_input_keys()) == {"a", "c"}
    assert set(st.get_registered_output_keys()) == {"b", "c"}
    sm = smach.StateMachine(outcomes=["done"])
    sm.userdata.a, sm.userdata.c = 1, 2
    with sm:
        smach.StateMachine.add("CB", st)
    assert sm.execute() == "done"
    assert sm.userdata.b == 3 and sm.userdata.c == 0


def test_cb_interface_on_method_binds_and_keeps_interface():
    class Robot:
        def __init__(self):
            self.calls = 0

        @smach.cb_interface(outcomes=["moved"])
        def move(self, ud):
            self.calls += 1
            return "moved"

    r = Robot()
    st = smach.CBState(r.move)
    assert st.get_registered_outcomes() == ("moved",)
    assert st.execute(smach.UserData()) == "moved"
    assert r.calls == 1


def test_has_smach_interface_false_for_plain_function():
    assert not smach.has_smach_interface(lambda ud: None)
    assert smach.has_smach_interface(smach.State())
