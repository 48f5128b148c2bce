"""Goals time out by task: an agent that never answers (a zombie) no longer keeps its work forever."""
from mbzirc_central_unit import constants as C
from mbzirc_central_unit.command import Command
from mbzirc_central_unit.goal_timeouts import TASK_TIMEOUT_S, GoalClock, timeout_of


def test_every_task_of_the_central_unit_has_a_bound():
    assert set(TASK_TIMEOUT_S) >= {C.TAKE_OFF, C.GO_HOME_AND_REFILL, C.SEARCH_INDOOR, C.EXTINGUISH_FACADE_FIRE}


def test_overdue_goal_is_reported_once_and_others_are_not():
    clock = GoalClock()
    slow = Command("1", C.TAKE_OFF)
    fine = Command("2", C.SEARCH_FACADE)
    in_flight = {"1": slow, "2": fine}
    clock.started(slow, 100.0)
    clock.started(fine, 100.0)
    assert clock.overdue(in_flight, 150.0) == []
    over = clock.overdue(in_flight, 100.0 + TASK_TIMEOUT_S[C.TAKE_OFF] + 1)
    assert [c for c, _ in over] == [slow]
    assert clock.overdue(in_flight, 100.0 + TASK_TIMEOUT_S[C.TAKE_OFF] + 2) == []      # once
    del in_flight["2"]                                                                 # finished
    assert clock.overdue(in_flight, 10000.0) == [] and clock.sent == {}


def test_time_going_back_restarts_the_count_and_hover_adds_its_duration():
    clock = GoalClock(scale=2.0)
    cmd = Command("1", C.HOVER, goal={"duration": 100.0})
    assert timeout_of(C.HOVER, cmd.goal, 2.0) == 2.0 * (TASK_TIMEOUT_S[C.HOVER] + 100.0)
    clock.started(cmd, 500.0)
    assert clock.overdue({"1": cmd}, 10.0) == []                    # simulation restarted at t=0
    assert clock.overdue({"1": cmd}, 10.0 + 2.0 * 160.0 + 1) != []
