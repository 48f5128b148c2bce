"""The step debugger without ROS: breakpoints, pause/step, forced outcomes, concurrence, preempt, caps."""
import json
import threading

import pytest

import smach
from smach_ros.debugger import StateDebugger, bounded_userdata, breakpoint_here


class Recorder(smach.State):
    """Appends its name to a shared log when it really runs."""

    def __init__(self, name, log, outcomes=("next", "other")):
        smach.State.__init__(self, outcomes=list(outcomes))
        self.name, self.log = name, log

    def execute(self, ud):
        self.log.append(self.name)
        return "next"


class Statuses:
    """Collects published status JSON; lets a test wait (on a condition, no sleeping) for one."""

    def __init__(self):
        self.items = []
        self.cond = threading.Condition()

    def publish(self, text):
        with self.cond:
            self.items.append(json.loads(text))
            self.cond.notify_all()

    def wait(self, pred, timeout=10.0):
        with self.cond:
            ok = self.cond.wait_for(lambda: any(pred(s) for s in self.items), timeout)
        assert ok, "no status matching; last: %s" % (self.items[-1:],)
        return [s for s in self.items if pred(s)][-1]


def paused_paths(status):
    return sorted(p["path"] for p in status["paused"])


def machine(log):
    sm = smach.StateMachine(outcomes=["done"])
    sm.userdata.counter = 3
    sm.userdata.secret = "s"
    with sm:
        smach.StateMachine.add("A", Recorder("A", log), transitions={"next": "B", "other": "C"})
        smach.StateMachine.add("B", Recorder("B", log), transitions={"next": "C", "other": "A"})
        smach.StateMachine.add("C", Recorder("C", log, ("next",)), transitions={"next": "done"})
    return sm


def concurrence_machine(log):
    """A machine whose one state CC runs the Recorders X and Y concurrently: (machine, CC)."""
    cc = smach.Concurrence(outcomes=["done"], default_outcome="done")
    with cc:
        smach.Concurrence.add("X", Recorder("X", log, ("next",)))
        smach.Concurrence.add("Y", Recorder("Y", log, ("next",)))
    sm = smach.StateMachine(outcomes=["done"])
    with sm:
        smach.StateMachine.add("CC", cc, transitions={"done": "done"})
    return sm, cc


def run(sm):
    box = {}
    t = threading.Thread(target=lambda: box.setdefault("outcome", sm.execute()), daemon=True)
    t.start()
    return t, box


def test_breakpoint_force_and_step():
    log, st = [], Statuses()
    sm = machine(log)
    dbg = StateDebugger(sm, "/R", st.publish, breakpoints=["/R/B", "/R/NOPE"], exclude_keys=["secret"])
    dbg.install()
    first = st.items[0]
    assert first["allowed"] and first["breakpoints"] == ["/R/B"] and "NOPE" in first["last"]["error"]
    t, box = run(sm)
    s = st.wait(lambda s: paused_paths(s) == ["/R/B"])
    assert log == ["A"]
    assert s["paused"][0]["outcomes"] == ["next", "other"]
    assert s["paused"][0]["userdata"] == {"counter": 3} and "secret: excluded" in s["paused"][0]["userdata_notes"]
    dbg.handle_command(json.dumps({"id": 1, "cmd": "force", "path": "/R/B", "outcome": "nope"}))
    assert st.items[-1]["last"]["ok"] is False and paused_paths(st.items[-1]) == ["/R/B"]
    dbg.handle_command(json.dumps({"id": 2, "cmd": "force", "path": "/R/B", "outcome": "other"}))
    # forced 'other' goes back to A without running B; B is a breakpoint again: pauses a second time
    st.wait(lambda s: s["last"].get("id") == 2 and s["last"]["ok"])
    st.items.clear()
    s = st.wait(lambda s: paused_paths(s) == ["/R/B"])
    assert log == ["A", "A"]
    dbg.handle_command(json.dumps({"cmd": "break", "path": "/R/B", "on": False}))
    dbg.handle_command(json.dumps({"cmd": "step", "path": "/R/B"}))  # run B, stop at the next state (C)
    st.wait(lambda s: paused_paths(s) == ["/R/C"])
    assert log == ["A", "A", "B"]
    dbg.handle_command(json.dumps({"cmd": "continue"}))
    t.join(5)
    assert box["outcome"] == "done" and log == ["A", "A", "B", "C"]
    dbg.uninstall()
    assert "execute" not in sm["B"].__dict__


def test_pause_command_and_declared_breakpoint():
    log, st = [], Statuses()
    sm = machine(log)
    breakpoint_here(sm["C"])
    dbg = StateDebugger(sm, "/", st.publish)
    assert "/C" in dbg.status()["breakpoints"]
    dbg.install()
    dbg.handle_command(json.dumps({"cmd": "pause"}))
    t, box = run(sm)
    st.wait(lambda s: paused_paths(s) == ["/A"])
    dbg.handle_command(json.dumps({"cmd": "continue", "path": "/A"}))
    st.wait(lambda s: paused_paths(s) == ["/C"])
    assert log == ["A", "B"]
    dbg.handle_command(json.dumps({"cmd": "continue", "path": "/C"}))
    t.join(5)
    assert box["outcome"] == "done"


def test_concurrence_children_pause_together():
    log, st = [], Statuses()
    sm, cc = concurrence_machine(log)
    dbg = StateDebugger(sm, "/R", st.publish, breakpoints=["/R/CC/X", "/R/CC/Y"])
    dbg.install()
    t, box = run(sm)
    st.wait(lambda s: paused_paths(s) == ["/R/CC/X", "/R/CC/Y"])
    assert sorted(cc.get_active_states()) == ["X", "Y"]
    dbg.handle_command(json.dumps({"cmd": "force", "path": "/R/CC/X", "outcome": "next"}))
    dbg.handle_command(json.dumps({"cmd": "continue", "path": "/R/CC/Y"}))
    t.join(5)
    assert box["outcome"] == "done" and log == ["Y"]


def test_preempt_releases_a_paused_state():
    st = Statuses()

    class Waits(smach.State):
        def __init__(self):
            smach.State.__init__(self, outcomes=["done", "preempted"])

        def execute(self, ud):
            if self.preempt_requested():
                self.service_preempt()
                return "preempted"
            return "done"

    sm = smach.StateMachine(outcomes=["done", "preempted"])
    with sm:
        smach.StateMachine.add("W", Waits())
    dbg = StateDebugger(sm, "/R", st.publish, breakpoints=["/R/W"])
    dbg.install()
    t, box = run(sm)
    st.wait(lambda s: paused_paths(s) == ["/R/W"])
    sm.request_preempt()
    t.join(5)
    assert box["outcome"] == "preempted"


def test_bad_commands_are_reported():
    st = Statuses()
    dbg = StateDebugger(machine([]), "/R", st.publish)
    for text, word in [("not json", "bad command"), ("[1]", "JSON object"), ('{"cmd": "rm"}', "unknown command"),
                       ('{"cmd": "break", "path": "/R/Z"}', "no state"), ('{"cmd": "continue", "path": "/R/A"}',
                                                                          "not paused")]:
        dbg.handle_command(text)
        assert st.items[-1]["last"]["ok"] is False and word in st.items[-1]["last"]["error"], text


def test_userdata_inspector_caps():
    shown, notes = bounded_userdata({"a": 1, "big": "x" * 100, "c": [1, 2], "d": "y" * 30, "skip": 0},
                                    exclude=["skip"], max_value_chars=50, max_total_chars=30)
    assert shown == {"a": 1, "c": [1, 2]}
    assert any(n.startswith("big: 102 JSON characters") for n in notes)
    assert any(n.startswith("d: not shown") for n in notes) and "skip: excluded" in notes


def test_the_last_status_sent_is_the_newest_when_children_resume_together():
    """A fresh-clone make test saw concurrent children still 'paused' in the viewer after continue: each
    resumed child publishes as it leaves, and the one that computed its status first could send it last."""
    log, sent = [], []
    first_computed = threading.Event()
    sm, cc = concurrence_machine(log)
    st = Statuses()
    dbg = StateDebugger(sm, "/R", st.publish, breakpoints=["/R/CC/X", "/R/CC/Y"])
    dbg.install()
    t, box = run(sm)
    st.wait(lambda s: paused_paths(s) == ["/R/CC/X", "/R/CC/Y"])

    def slow_publish(text):             # the first status computed after the continue is sent late
        if not first_computed.is_set():
            first_computed.set()
            threading.Event().wait(0.2)
        sent.append(json.loads(text))
    dbg._publish = slow_publish
    dbg.handle_command(json.dumps({"cmd": "continue"}))
    t.join(5)
    assert box["outcome"] == "done" and sorted(log) == ["X", "Y"]
    assert sent[-1]["paused"] == []
