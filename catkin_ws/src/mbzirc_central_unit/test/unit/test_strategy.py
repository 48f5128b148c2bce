"""The C3 strategy: assignment, refill and reassignment, first floor last, silent agents, restart."""
import math

import pytest

from mbzirc_arena import c3
from fake_mission import FakeMission, TRUE_FIRES

from mbzirc_central_unit import constants as C
from mbzirc_central_unit import geometry as G
from mbzirc_central_unit.command import Command
from mbzirc_central_unit.strategy import Strategy, StrategyParams
from mbzirc_central_unit.world_model import AgentView, FireView, WorldView, facade_floor, fire_kind


def _tasks(cmds):
    return {c.agent_id: c.task for c in cmds}


def test_first_tick_ugv_indoors_and_uavs_take_off_at_distinct_altitudes():
    m = FakeMission()
    cmds = m.strategy.decide(m.world())
    assert _tasks(cmds) == {"0": C.SEARCH_INDOOR, "1": C.TAKE_OFF, "2": C.TAKE_OFF, "3": C.TAKE_OFF}
    assert [c.goal["floor"] for c in cmds if c.agent_id == "0"] == [0]
    heights = [c.goal["height"] for c in cmds if c.task == C.TAKE_OFF]
    assert len(set(heights)) == 3


def test_water_uavs_get_different_floors_first_floor_last():
    m = FakeMission()
    m.step()  # take-offs
    cmds = {c.agent_id: c for c in m.step()}
    floors = {cmds["2"].target[1], cmds["3"].target[1]}
    assert cmds["2"].task == C.FOLLOW_PATH and cmds["3"].task == C.FOLLOW_PATH
    assert floors == {2, 0}  # floor 1 (wind gusts) is nobody's first floor
    assert m.strategy.floor_owner == {2: "2", 0: "3"}


def test_transits_change_altitude_only_in_an_elevator_and_not_both_in_the_same():
    m = FakeMission()
    m.step()
    used = {}
    for c in m.step():
        if c.task != C.FOLLOW_PATH:
            continue
        path = [p[:3] for p in c.goal["path"]]
        vertical = [(p, q) for p, q in zip(path, path[1:]) if abs(p[2] - q[2]) > 1e-6]
        assert vertical, "a transit to another floor must climb or descend somewhere"
        elevators = G.elevator_points()
        for p, q in vertical:
            e = [i for i, xy in enumerate(elevators) if math.dist(p[:2], xy) < 1e-6 and math.dist(q[:2], xy) < 1e-6]
            assert e == [c.goal["_elevator"]]
        used[c.agent_id] = c.goal["_elevator"]
    assert sorted(used.values()) == [0, 1]  # two UAVs in transit at once take different elevators


def test_facade_search_starts_at_the_end_nearest_the_uav():
    s = Strategy()
    for start, expected_first in (((5.0, 25.0, 1.5), "C"), ((30.0, 25.0, 1.5), "A")):
        a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *start, ual_state=C.UAL_FLYING_AUTO, water_level=2.0,
                      last_seen=0.0)
        s = Strategy(StrategyParams(floor_priority=(0,)))
        cmd = s.decide(WorldView(0.0, {"2": a}, {}))[0]
        first = cmd.goal["path"][-1]
        holder = [h for h in c3.FACADE_HOLDERS if G.floor_of(h[2]) == 0 and
                  math.dist(G.viewpoint(h)[:3], first[:3]) < 1e-6][0]
        assert G.facade_of(holder) == expected_first


def test_whole_mission_puts_out_all_fires_with_refills():
    m = FakeMission()
    steps = m.run()
    assert steps > 0, [f"{c.agent_id}:{c.task}" for c, _ in m.log[-20:]]
    tasks = [c.task for c, _ in m.log]
    assert tasks.count(C.GO_HOME_AND_REFILL) >= 2  # facade fires need 1.5 L with 1 L tanks; a new blanket
    done_by = {c.target: c.agent_id for c, ok in m.log if c.task == C.EXTINGUISH_INDOOR_FIRE}
    assert done_by[6] == "0"  # the UGV takes the ground floor indoors
    assert {done_by[7], done_by[8]} <= {"2", "3"}


def test_blanket_uav_gets_a_new_blanket_between_ground_fires():
    m = FakeMission()
    m.run()
    seq = [c.task for c, _ in m.log if c.agent_id == "1"]
    i = seq.index(C.EXTINGUISH_GROUND_FIRE)
    j = seq.index(C.EXTINGUISH_GROUND_FIRE, i + 1)
    assert C.GO_HOME_AND_REFILL in seq[i:j]


def test_empty_tank_goes_home_through_elevator_and_releases_the_floor():
    m = FakeMission()
    m.step(); m.step()
    a = m.agents["2"]
    a.water_level = 0.0
    cmd = {c.agent_id: c for c in m.step()}["2"]
    assert cmd.task == C.FOLLOW_PATH  # leaves via the elevator at its own altitude first
    assert cmd.goal["path"][-1][2] == m.strategy.altitude("2")
    assert "2" not in m.strategy.floor_owner.values()
    cmd = {c.agent_id: c for c in m.step()}["2"]
    assert cmd.task == C.GO_HOME_AND_REFILL


def test_silent_agent_floor_is_reassigned_and_agent_gets_work_on_return():
    m = FakeMission()
    m.strategy.p.floor_priority = (2, 0, 1)
    m.step(); m.step(); m.step()  # take off, transit, search
    owner2 = [f for f, o in m.strategy.floor_owner.items() if o == "2"]
    assert owner2 == [2]
    m.silent.add("2")
    for _ in range(3):
        m.step()
    assert m.strategy.floor_owner.get(2) != "2"
    assert "2" not in {c.agent_id for c, _ in m.log[-6:]}
    m.silent.clear()
    got = []
    for _ in range(3):
        got += [c for c in m.step() if c.agent_id == "2"]
    assert got, "a returning agent gets work again"


def test_silent_agent_work_goes_to_the_other_uav():
    m = FakeMission()
    m.fail_tasks.add(("3", C.EXTINGUISH_FACADE_FIRE))  # uav 3 never manages to put its fire out
    m.silent.add("2")
    m.agents["2"].last_seen = -100
    steps = m.run(400)
    searched = {c.target for c, ok in m.log if c.task == C.SEARCH_FACADE and c.agent_id == "3"}
    assert searched >= {0, 1, 2}
    assert steps == -1  # uav 3 cannot extinguish and uav 2 is silent: honest failure
    assert all(c.agent_id != "2" for c, _ in m.log)


def test_failed_task_is_given_up_and_taken_by_another_agent():
    m = FakeMission()
    m.fail_tasks.add(("2", C.SEARCH_FACADE))
    steps = m.run(400)
    assert steps > 0
    searched_ok = {c.target for c, ok in m.log if c.task == C.SEARCH_FACADE and ok}
    assert 2 in searched_ok  # floor 2, uav 2's first floor, was searched by uav 3


def test_second_search_then_indoor():
    m = FakeMission()
    # No facade fire on floor 0 is ever found: floor 0 gets a second search before any indoor floor.
    fid = [k for k, v in TRUE_FIRES.items() if v[0] == C.KIND_FACADE and G.floor_of(v[1][2]) == 0][0]
    saved = TRUE_FIRES.pop(fid)
    try:
        m.run(200)
    finally:
        TRUE_FIRES[fid] = saved
    facade0 = [i for i, (c, ok) in enumerate(m.log) if c.task == C.SEARCH_FACADE and c.target == 0]
    indoor = [i for i, (c, ok) in enumerate(m.log) if c.task == C.ENTER_BUILDING]
    assert len(facade0) == 2
    assert indoor and min(indoor) > facade0[1] or all(
        m.strategy.facade_searches[f] >= 1 for f in (1, 2))


def test_restart_rebuilds_floor_ownership_from_data_feeds():
    m = FakeMission()
    for _ in range(3):
        m.step()
    # A fresh strategy (restarted node): uav 2 is busy searching floor 2's facade, uav 3 idle near home.
    a2 = m.agents["2"]
    a2.is_idle, a2.active_task = False, C.SEARCH_FACADE
    a2.x, a2.y, a2.z = 26.7, 12.7, 10.5
    s = Strategy()
    cmds = {c.agent_id: c for c in s.decide(m.world())}
    assert s.floor_owner.get(2) == "2"
    assert "2" not in cmds
    if "3" in cmds and cmds["3"].target is not None:
        floor = cmds["3"].target[1] if isinstance(cmds["3"].target, tuple) else cmds["3"].target
        assert floor != 2


def test_known_fire_is_approached_then_extinguished():
    s = Strategy()
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *G.viewpoint((24.2, 8.2, 8.25))[:3],
                  ual_state=C.UAL_FLYING_AUTO, water_level=1.0, last_seen=0.0)
    w = WorldView(0.0, {"2": a}, {7: FireView(7, 24.2, 8.2, 8.25, C.KIND_FACADE)})
    c1 = s.decide(w)[0]
    assert (c1.task, c1.goal["fire_id"]) == (C.GO_TO_FACADE_FIRE, 7)
    s.on_sent(c1); s.on_result(c1, True)
    c2 = s.decide(w)[0]
    assert (c2.task, c2.goal["fire_id"]) == (C.EXTINGUISH_FACADE_FIRE, 7)


def test_extinguished_fires_and_their_stray_tracks_are_not_targets():
    s = Strategy(StrategyParams(facade_searches=0, indoor_floors=()))
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, 0, 0, 5, ual_state=C.UAL_FLYING_AUTO, water_level=1.0,
                  last_seen=0.0)
    fires = {1: FireView(1, 24.2, 8.2, 8.25, C.KIND_FACADE, C.STATUS_EXTINGUISHED),
             2: FireView(2, 24.2, 9.0, 8.0, C.KIND_FACADE, C.STATUS_LOST)}  # a stray track of fire 1
    cmds = s.decide(WorldView(0.0, {"2": a}, fires))
    assert all(c.task in (C.FOLLOW_PATH, C.GO_HOME_AND_REFILL) and c.target in (None, ("transit", None))
               for c in cmds)


def test_realistic_102_a_facade_fire_read_low_stays_on_its_holders_storey_and_the_storey_below_is_searched():
    layout_holders = StrategyParams().layout.facade_holders
    c_3 = (11.4, 14.5, 10.5)                       # a floor-2 holder, 0.5 m above the storey's floor height
    estimate = (11.6, 14.4, 9.9)                   # its fire's estimate with the GNSS height 0.6 m low
    assert c_3 in [tuple(h[:3]) for h in layout_holders]
    assert facade_floor(estimate, layout_holders) == 2
    assert facade_floor(estimate, []) is None
    out = FireView(7, *estimate, C.KIND_FACADE, C.STATUS_EXTINGUISHED,
                   holder_floor=facade_floor(estimate, layout_holders))
    assert out.floor == 2
    s = Strategy(StrategyParams())
    world = WorldView(0.0, {}, {7: out})
    assert world.extinguished_on(C.KIND_FACADE, 2) and not world.extinguished_on(C.KIND_FACADE, 1)
    # before: the fire counted on floor 1, whose facade was then never searched (one fire per storey)
    assert 1 in s.water.facade_floors_open(world)


def _in_floor2_east_room(fire_x):
    uav = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, 19.9, 16.5, 11.5, ual_state=C.UAL_FLYING_AUTO,
                    water_level=2.0, last_seen=0.0)
    return WorldView(0.0, {"3": uav}, {20: FireView(20, fire_x, 16.5, 11.5, C.KIND_INDOOR)})


def test_realistic_107_an_indoor_fire_estimated_in_its_wall_is_put_out_from_the_room_that_found_it():
    """The east room's fire on the interior wall (its east face at x 17.9), estimated 0.2 m into the wall:
    no room sees that point. Before: not a target, the UAV beside it left the floor for other work."""
    s = Strategy(StrategyParams())
    found = Command("3", C.SEARCH_INDOOR, {"floor": 2, "path": []}, "searching floor 2 indoors (room 1)", (2, 1))
    s.on_sent(found)
    s.on_result(found, True, {"fire_ids": [20]}, now=0.0)
    s.book.pending_ids.clear()
    [cmd] = s.decide(_in_floor2_east_room(17.7))
    assert cmd.task == C.EXTINGUISH_INDOOR_FIRE and cmd.goal["fire_id"] == 20, cmd
    # with no search on record, the holder's viewpoint still puts it in the east room
    [cmd] = Strategy(StrategyParams()).decide(_in_floor2_east_room(17.7))
    assert cmd.task == C.EXTINGUISH_INDOOR_FIRE, cmd


def test_fire_kind_by_position_when_the_estimator_gives_no_subtype():
    assert fire_kind(C.SUBTYPE_UNKNOWN, 1.0, 14.0, 0.0) == C.KIND_GROUND
    assert fire_kind(C.SUBTYPE_UNKNOWN, 11.4, 8.5, 6.0) == C.KIND_FACADE
    assert fire_kind(C.SUBTYPE_UNKNOWN, 11.1, 8.5, 6.0) == C.KIND_FACADE
    assert fire_kind(C.SUBTYPE_UNKNOWN, 17.0, 12.0, 6.0) == C.KIND_INDOOR
    assert fire_kind(C.SUBTYPE_GROUND, 17.0, 12.0, 6.0) == C.KIND_GROUND


def test_uavs_take_the_ground_floor_indoors_when_the_ugv_is_gone():
    m = FakeMission(Strategy(StrategyParams(uavs_take_ground_floor_indoors=True)))
    m.silent.add("0")
    m.agents["0"].last_seen = -100.0
    steps = m.run(400)
    assert steps > 0
    assert all(c.agent_id != "0" for c, _ in m.log)
    entered = {c.target for c, _ in m.log if c.task == C.ENTER_BUILDING}
    assert any(t[0] == 0 for t in entered)


def test_low_tank_refills_before_a_new_fire_job():
    s = Strategy()
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, -3.0, 20.0, s.altitude("2") - 0.5,   # near its own altitude
                  ual_state=C.UAL_FLYING_AUTO, water_level=0.5, last_seen=0.0)
    w = WorldView(0.0, {"2": a}, {7: FireView(7, 24.2, 8.2, 8.25, C.KIND_FACADE)})
    cmd = s.decide(w)[0]
    assert cmd.task == C.GO_HOME_AND_REFILL
    s2 = Strategy()
    a.water_level = 1.5
    assert s2.decide(w)[0].task == C.FOLLOW_PATH


def test_layout_from_the_simulator_world_file_matches_the_defaults():
    import os
    import yaml
    from mbzirc_central_unit.layout import Layout, load_world
    path = os.path.join(os.path.dirname(__file__), "..", "..", "..", "ual_sim", "src", "ual_sim", "worlds",
                        "c3_default.yaml")
    with open(path, encoding="utf-8") as f:
        loaded = load_world(yaml.safe_load(f))
    default = Layout()
    assert sorted(loaded.windows) == sorted(default.windows)
    assert sorted(loaded.facade_holders) == sorted(default.facade_holders)
    assert {f: [r.entry for r in rs] for f, rs in loaded.rooms.items()} == \
        {f: [r.entry for r in rs] for f, rs in default.rooms.items()}
    assert set(loaded.rooms) == {0, 1, 2} and len(loaded.rooms[1]) == 2 and len(loaded.rooms[2]) == 2


def test_lost_fires_are_targets_unless_next_to_one_already_out():
    w = WorldView(0.0, {}, {1: FireView(1, 17.7, 8.5, 6.5, C.KIND_INDOOR, C.STATUS_LOST),
                            2: FireView(2, 24.2, 17.75, 6.0, C.KIND_FACADE, C.STATUS_EXTINGUISHED),
                            3: FireView(3, 24.2, 18.5, 6.2, C.KIND_FACADE, C.STATUS_LOST)})
    assert [f.fire_id for f in w.fires_of(C.KIND_INDOOR)] == [1]
    assert w.fires_of(C.KIND_FACADE) == []


def test_agent_waits_for_the_fires_its_search_reported():
    s = Strategy()
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *G.viewpoint((24.2, 8.2, 8.25))[:3],
                  ual_state=C.UAL_FLYING_AUTO, water_level=2.0, last_seen=0.0)
    cmd = s.decide(WorldView(0.0, {"2": a}, {}))[0]
    s.on_result(cmd, True, {"fire_ids": [7]})
    assert s.decide(WorldView(0.0, {"2": a}, {})) == []   # fire 7 not in /estimated_objects yet
    w = WorldView(0.0, {"2": a}, {7: FireView(7, 24.2, 8.2, 8.25, C.KIND_FACADE)})
    assert s.decide(w)[0].goal["fire_id"] == 7


def test_a_crashed_uav_that_cannot_take_off_releases_its_floor():
    m = FakeMission()
    m.step(); m.step()
    floor = [f for f, o in m.strategy.floor_owner.items() if o == "3"][0]
    a = m.agents["3"]
    a.ual_state = C.UAL_LANDED_DISARMED
    m.fail_tasks.update({("3", t) for t in C.UAV_TASKS})
    for _ in range(8):
        m.step()
    assert m.strategy.broken("3")
    assert m.strategy.floor_owner.get(floor) != "3"
    n = len([c for c, _ in m.log if c.agent_id == "3"])
    m.step(); m.step()
    assert len([c for c, _ in m.log if c.agent_id == "3"]) == n  # no more goals for it


def test_exit_from_the_building_is_one_straight_waypoint_at_a_time():
    s = Strategy()
    room = s.p.layout.rooms[2][0]
    deep = room.path[0]
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *deep[:3], ual_state=C.UAL_FLYING_AUTO, water_level=0.0,
                  last_seen=0.0)
    cmd = s.decide(WorldView(0.0, {"2": a}, {}))[0]
    assert cmd.task == C.SEARCH_INDOOR and len(cmd.goal["path"]) == 1
    assert math.dist(cmd.goal["path"][0][:3], room.exit_start) < 1e-6
    s.on_result(cmd, True)
    a.x, a.y, a.z = room.exit_start
    cmd = s.decide(WorldView(1.0, {"2": a}, {}))[0]
    assert cmd.task == C.SEARCH_INDOOR and math.dist(cmd.goal["path"][0][:3], room.entry[:3]) < 1e-6


def test_realistic_107_a_uav_at_the_way_outs_start_with_its_reported_height_off_goes_on_out():
    """Indoors the agents fly heights by the altimeter: the reported (GNSS) height stays off the commanded
    one by the vertical GNSS error. Before: the central unit sent the same first waypoint 20 times (2 min)."""
    s = Strategy()
    room = s.p.layout.rooms[2][1]
    x, y, z = room.exit_start
    a = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, x + 0.2, y, z + 0.6, ual_state=C.UAL_FLYING_AUTO,
                  water_level=0.0, last_seen=0.0)
    cmd = s.decide(WorldView(0.0, {"3": a}, {}))[0]
    assert cmd.task == C.SEARCH_INDOOR and math.dist(cmd.goal["path"][0][:3], room.entry[:3]) < 1e-6, cmd


def test_the_way_out_starts_deeper_inside_than_the_way_in_ended():
    """Realistic seed 103: the move to 1.5 m inside facade C's window, a metre off on GNSS, put a leaving
    UAV into the wall's inner face. The way out starts 2.5 m inside, on the window's normal."""
    from mbzirc_central_unit.indoor_plan import EXIT_DEPTH, WINDOW_DEPTH
    for rooms in Strategy().p.layout.rooms.values():
        for room in rooms:
            wall_to_entry = math.dist(room.inner[:2], room.entry[:2])       # WINDOW_DEPTH + the standoff
            assert math.dist(room.exit_start[:2], room.entry[:2]) == pytest.approx(
                wall_to_entry + EXIT_DEPTH - WINDOW_DEPTH)
            assert math.dist(room.exit_start[:2], room.inner[:2]) == pytest.approx(EXIT_DEPTH - WINDOW_DEPTH)


def test_a_uav_that_flew_and_is_uninitialized_again_has_crashed():
    m = FakeMission()
    m.step(); m.step()
    floor = [f for f, o in m.strategy.floor_owner.items() if o == "2"][0]
    m.agents["2"].ual_state = C.UAL_UNINITIALIZED   # the simulator's crash state
    m.step()
    assert "2" in m.strategy.crashed and m.strategy.broken("2")
    assert m.strategy.floor_owner.get(floor) != "2"
    # never flown, UNINITIALIZED at start-up: not a crash
    m2 = FakeMission()
    m2.agents["3"].ual_state = C.UAL_UNINITIALIZED
    m2.step()
    assert not m2.strategy.crashed


def test_a_crashed_ugv_gets_no_more_goals():
    m = FakeMission()
    m.agents["0"].ual_state = C.UAL_FLYING_AUTO   # driving
    m.strategy.decide(m.world())
    m.agents["0"].ual_state = C.UAL_UNINITIALIZED
    m.strategy.in_flight.clear()
    cmds = m.strategy.decide(m.world())
    assert "0" in m.strategy.crashed and all(c.agent_id != "0" for c in cmds)


def test_fire_tracks_far_from_every_holder_are_not_targets():
    s = Strategy(StrategyParams(facade_searches=0, indoor_floors=()))
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, 30.0, 25.0, 6.0, ual_state=C.UAL_FLYING_AUTO,
                  water_level=2.0, last_seen=0.0)
    drifted = FireView(9, 24.2, 12.0, 6.0, C.KIND_FACADE)   # 4.5 m from the nearest floor-1 holder on D
    cmds = s.decide(WorldView(0.0, {"2": a}, {9: drifted}))
    assert cmds and all("fire 9" not in c.reason and c.goal.get("fire_id") != 9 for c in cmds)
    near = FireView(9, 24.3, 17.5, 6.1, C.KIND_FACADE)      # D_0 (24.2, 17.75, 6.0)
    s2 = Strategy(StrategyParams(facade_searches=0, indoor_floors=()))
    cmd = s2.decide(WorldView(0.0, {"2": a}, {9: near}))[0]
    assert cmd.target == ("transit", 1) and "fire 9" in cmd.reason


def test_an_indoor_fire_estimated_slightly_into_its_wall_is_put_out_from_the_room_in_front():
    s = Strategy()
    layout = s.p.layout
    room = layout.rooms[1][0]                      # the west room, in front of in1_w (17.7, 8.5, 6.5)
    view = room.path[0]
    fire = FireView(40, 17.78, 8.6, 6.4, C.KIND_INDOOR)   # estimated 8 cm into the interior wall
    assert layout.room_for(1, fire.position) == 0
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *view[:3], ual_state=C.UAL_FLYING_AUTO,
                  water_level=2.0, last_seen=0.0)
    cmd = s.decide(WorldView(0.0, {"2": a}, {40: fire}))[0]
    assert (cmd.task, cmd.goal["fire_id"]) == (C.EXTINGUISH_INDOOR_FIRE, 40)
    # The same fire is not "seen" from the east room, behind the wall.
    east = layout.rooms[1][1].path[0]
    assert not layout.clear_indoors(1, east[:3], fire.position)



def test_an_indoor_fire_estimated_past_its_walls_middle_is_not_flown_to_through_the_wall():
    """Realistic seed 103: fire in2_w (west face of the interior wall x 17.7-17.9) estimated 5 cm past the
    wall's middle line, as if on the east face: UAVs in the east room were sent to its viewpoint, west of
    the wall, by a straight leg through the wall. The fire's side is its viewpoint's: the UAV goes round,
    out of the east room, to the west room's window."""
    s = Strategy()
    layout = s.p.layout
    west, east = layout.rooms[2][0], layout.rooms[2][1]
    fire = FireView(43, 17.85, 8.5, 11.5, C.KIND_INDOOR)
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *east.path[0][:3], ual_state=C.UAL_FLYING_AUTO,
                  water_level=2.0, last_seen=0.0)
    assert layout.clear_indoors(2, a.position, fire.position)             # the estimate looks in sight
    assert not layout.clear_indoors(2, a.position, west.path[0][:3])      # its viewpoint is not
    cmd = s.decide(WorldView(0.0, {"2": a}, {43: fire}))[0]
    legs = cmd.goal.get("path", [])
    assert cmd.task != C.EXTINGUISH_INDOOR_FIRE, cmd
    assert all(layout.clear_indoors(2, a.position, p[:3]) for p in legs[:1]), (cmd.reason, legs)
    assert "leaving" in cmd.reason or cmd.target[0] == "exit" or "window" in cmd.reason, cmd.reason


def test_an_indoor_fire_is_put_out_from_its_viewpoint_not_from_the_window():
    """Inside the room but at the window: first to the viewpoint in front of the holder (water along the
    wall's normal), then extinguish from there."""
    s = Strategy()
    room = s.p.layout.rooms[1][0]
    view = room.path[0]
    fire = FireView(41, 17.75, 8.5, 6.5, C.KIND_INDOOR)
    a = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *room.inner, ual_state=C.UAL_FLYING_AUTO,
                  water_level=2.0, last_seen=0.0)
    assert math.dist(room.inner, view[:3]) > 1.0
    cmd = s.decide(WorldView(0.0, {"2": a}, {41: fire}))[0]
    assert cmd.task == C.SEARCH_INDOOR and cmd.goal["path"] == [view]
    s.on_sent(cmd); s.on_result(cmd, True)
    at_view = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *view[:3], ual_state=C.UAL_FLYING_AUTO,
                        water_level=2.0, last_seen=0.0)
    cmd = s.decide(WorldView(1.0, {"2": at_view}, {41: fire}))[0]
    assert (cmd.task, cmd.goal["fire_id"]) == (C.EXTINGUISH_INDOOR_FIRE, 41)


def test_a_floor_stays_taken_while_the_uav_that_left_it_is_still_there():
    """UAV 2 leaves floor 1 through its window (it owns nothing any more); UAV 3 is not sent to that
    floor's window until UAV 2 is away from the building, or they would block each other there."""
    s = Strategy(StrategyParams(facade_searches=0))
    room = s.p.layout.rooms[1][0]
    fire = FireView(42, 17.75, 8.5, 6.5, C.KIND_INDOOR)
    leaving = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *room.entry[:3], ual_state=C.UAL_FLYING_AUTO,
                        water_level=0.3, last_seen=0.0)
    idle = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, -5.0, 0.0, 8.0, ual_state=C.UAL_FLYING_AUTO,
                     water_level=2.0, last_seen=0.0)
    cmds = {c.agent_id: c for c in s.decide(WorldView(0.0, {"2": leaving, "3": idle}, {42: fire}))}
    assert s.indoor_owner.get(1) != "3"
    assert "indoor fire 42" not in cmds["3"].reason and "floor 1" not in cmds["3"].reason
    away = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, -5.0, 3.0, 4.0, ual_state=C.UAL_FLYING_AUTO,
                     water_level=0.3, last_seen=1.0)
    s2 = Strategy(StrategyParams(facade_searches=0))
    cmds = {c.agent_id: c for c in s2.decide(WorldView(1.0, {"2": away, "3": idle}, {42: fire}))}
    assert s2.indoor_owner.get(1) == "3" and "indoor fire 42" in cmds["3"].reason


def test_no_goal_before_the_robot_s_autopilot_reported():
    """At start-up the data_feed may come before the UAL's first state (UNINITIALIZED): no goal then
    (it would fail at once, and three failures made the UGV give up its job)."""
    s = Strategy()
    ugv = AgentView("0", C.ROBOT_UGV, C.PAYLOAD_WATER, 4.0, -4.0, 0.0, ual_state=C.UAL_UNINITIALIZED,
                    water_level=2.0, last_seen=0.0)
    assert s.decide(WorldView(0.0, {"0": ugv}, {})) == []
    ugv.ual_state = C.UAL_LANDED_ARMED
    (cmd,) = s.decide(WorldView(0.5, {"0": ugv}, {}))
    assert cmd.agent_id == "0" and cmd.task == C.SEARCH_INDOOR


def test_no_goal_before_the_robot_s_data_feed_carried_a_pose():
    """Ideal seed 7: a water UAV's first data_feeds (UAL ready, no pose yet, water 0) got three refills at
    2 s, each aborted 'home unknown (no pose yet)'; with three failures it gave refilling up, and after its
    first fire (0.56 L left) it hovered idle for the last 640 s of the trial. No goal before a pose."""
    s = Strategy()
    uav = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, 0.0, 0.0, 0.0, ual_state=C.UAL_LANDED_ARMED,
                    water_level=0.0, last_seen=0.0, reported=False)
    for t in (0.0, 0.5, 1.0):
        assert s.decide(WorldView(t, {"2": uav}, {})) == []
    uav.x, uav.y, uav.reported = 0.0, 8.0, True
    (cmd,) = s.decide(WorldView(1.5, {"2": uav}, {}))
    assert cmd.agent_id == "2"


def test_no_goal_while_the_agent_says_it_has_no_trusted_pose():
    """Explore + GNSS-denied seed 101: a UAV whose SLAM pose had jumped indoors got 7 goals in 8 s, each
    aborted 'no trusted pose', each stopping it where it was. While its data_feed says NO_TRUSTED_POSE it gets
    none (it backs out the way it came); once the pose is back, it does."""
    s = Strategy()
    uav = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, 16.0, 10.0, 7.5, ual_state=C.UAL_FLYING_AUTO,
                    water_level=2.0, last_seen=0.0,
                    active_sub_state=f"{C.NO_TRUSTED_POSE}: no GNSS fix and localization/source says none")
    for t in (0.0, 0.5, 1.0):
        assert s.decide(WorldView(t, {"2": uav}, {})) == []
    uav.active_sub_state = ""
    (cmd,) = s.decide(WorldView(1.5, {"2": uav}, {}))
    assert cmd.agent_id == "2"


def test_a_transit_starting_near_the_ground_climbs_first():
    s = Strategy()
    a = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, 23.7, 21.5, 0.7, ual_state=C.UAL_FLYING_AUTO,
                  water_level=0.0, last_seen=0.0)
    cmd = s.decide(WorldView(0.0, {"3": a}, {}))[0]
    assert cmd.task == C.FOLLOW_PATH
    first = cmd.goal["path"][0]
    assert first[:2] == (23.7, 21.5) and first[2] >= 1.5
    assert all(p[2] >= 1.5 for p in cmd.goal["path"])


def test_a_room_just_entered_is_searched_before_the_uav_leaves_for_other_work():
    """Ideal seeds 2 and 4, realistic 107 and 103 (benchmark): a UAV that had just come in through a window to
    search a room left at once for a facade fire of another floor or an indoor fire elsewhere, and the room was
    searched a minute or more later by a UAV flying there again (a room's search takes 5-20 s; out through the
    window and back in again 60-100 s). Rule: the room just entered is searched first."""
    s = Strategy(StrategyParams())
    room = s.p.layout.rooms[2][0]
    enter = Command("3", C.ENTER_BUILDING, {"floor": 2, "entry": room.entry},
                    "entering floor 2 through the window (to search room 0)", (2, 0))
    s.on_sent(enter)
    s.on_result(enter, True, {}, now=10.0)
    uav = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, *room.inner[:3], ual_state=C.UAL_FLYING_AUTO,
                    water_level=2.0, last_seen=10.0)
    facade_fire_floor_1 = FireView(12, 24.2, 8.2, 8.25, C.KIND_FACADE)
    [cmd] = s.decide(WorldView(10.0, {"3": uav}, {12: facade_fire_floor_1}))
    assert (cmd.task, cmd.target) == (C.SEARCH_INDOOR, (2, 0)), cmd   # before: leaving floor 2 for fire 12
    s.on_result(cmd, True, {}, now=20.0)
    uav.last_seen = 20.0
    [cmd] = s.decide(WorldView(20.0, {"3": uav}, {12: facade_fire_floor_1}))
    assert cmd.target != (2, 0), cmd                   # searched: now it leaves for the fire


def test_a_uav_inside_a_floor_puts_out_the_indoor_fire_it_found_there_before_facade_work():
    """Realistic seed 201 (738dab6): UAV 2, full tank, found in2_w in the room it searched on floor 2 and flew
    out at once to top up facade fire D_4 on floor 1 (already out); in2_w got its first water 250 s later.
    Rule: a known indoor fire on the floor the UAV is inside comes before any job elsewhere (it is seconds
    away; out through the window and back in again costs 60-100 s)."""
    s = Strategy(StrategyParams())
    room = s.p.layout.rooms[2][0]
    found = Command("2", C.SEARCH_INDOOR, {"floor": 2, "path": list(room.path)},
                    "searching floor 2 indoors (room 0)", (2, 0))
    s.on_sent(found)
    s.on_result(found, True, {"fire_ids": [26]}, now=10.0)
    s.book.pending_ids.clear()
    uav = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *room.inner[:3], ual_state=C.UAL_FLYING_AUTO,
                    water_level=2.0, last_seen=10.0)
    holder = min(s.p.layout.indoor_holders, key=lambda h: math.dist(h[:3], room.inner[:3]))
    fires = {15: FireView(15, 24.2, 8.2, 8.25, C.KIND_FACADE),              # floor 1's facade fire, to top up
             26: FireView(26, *holder[:3], C.KIND_INDOOR)}                # the fire just found on floor 2
    [cmd] = s.decide(WorldView(10.0, {"2": uav}, fires))
    assert cmd.goal.get("fire_id") == 26 or cmd.target == ("view", 26), cmd   # before: leaving for fire 15


def test_a_fire_seen_through_a_doorway_is_reached_through_the_room_it_is_watered_from():
    """Realistic seed 109 (benchmark on 19ac3a6): fire 20, on floor 2's south room's wall, was found by a
    search of the north room (through the doorway). The north room was the way to it, but from there no clear
    way led to its viewpoint: UAV 2 entered the north room, was sent out through the same window, in again,
    6 times in 300 s, and floor 1 was never searched. Rule: the finding room is the way only when the
    fire's viewpoint is reachable from it; else the viewpoint's room."""
    s = Strategy(StrategyParams())
    south, north = s.p.layout.rooms[2]
    holder = min((h for h in s.p.layout.indoor_holders if G.floor_of(h[2]) == 2),
                 key=lambda h: math.dist(h[:2], south.inner[:2]))
    assert s.p.layout.room_for(2, holder[:3]) == 0
    found = Command("2", C.SEARCH_INDOOR, {"floor": 2, "path": list(north.path)},
                    "searching floor 2 indoors (room 1)", (2, 1))
    s.on_sent(found)
    s.on_result(found, True, {"fire_ids": [20]}, now=10.0)
    s.book.pending_ids.clear()
    fire = FireView(20, *holder[:3], C.KIND_INDOOR)
    # out of the north room, in front of the south room's window: in through it (before: round to the north)
    uav = AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *south.entry[:3], ual_state=C.UAL_FLYING_AUTO,
                    water_level=2.0, last_seen=20.0)
    [cmd] = s.decide(WorldView(20.0, {"2": uav}, {20: fire}))
    assert (cmd.task, cmd.target) == (C.ENTER_BUILDING, (2, 0)), cmd


def test_realistic_108_a_facade_floor_reached_for_its_search_is_searched_before_jobs_elsewhere():
    """Realistic seed 108: facade fire 2 (D_3, floor 2) was misplaced (never seen hot from its watering pose), its
    floor owed a search again; UAV 3 flew to floor 2's search start for it and, once there, was sent to fires
    of floor 1 found meanwhile (at 293 s facade fire 33, at 649 s indoor fire 41): D_3 never searched, 0.0."""
    not_hot = ("fire 2 not seen hot from the watering pose: not judged out: 3 s of water on its hole (seen "
               "through) without a hot answer there; left active")
    s = Strategy()
    for floor in (0, 1, 2):
        s.book.facade_searches[floor] = 1
    for agent in ("2", "2"):
        cmd = Command(agent, C.EXTINGUISH_FACADE_FIRE, {"fire_id": 2, "_floor": 2}, "water on facade fire 2", 2)
        s.on_sent(cmd)
        s.on_result(cmd, False, {"message": not_hot})
    start = G.facade_search_path(2, s.p.layout.facade_holders)[0]
    a = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, *start[:3], ual_state=C.UAL_FLYING_AUTO, water_level=2.0,
                  last_seen=0.0)
    fires = {2: FireView(2, 24.2, 17.6, 12.5, C.KIND_FACADE), 33: FireView(33, 24.2, 8.2, 8.25, C.KIND_FACADE),
             41: FireView(41, 17.7, 8.5, 6.5, C.KIND_INDOOR)}
    world = WorldView(0.0, {"3": a}, fires)
    transit = Command("3", C.FOLLOW_PATH, {"path": [start]}, "to floor 2 via the elevator", ("transit", 2))
    s.on_sent(transit)
    s.on_result(transit, True, {})
    [cmd] = s.decide(world)
    assert (cmd.task, cmd.target) == (C.SEARCH_FACADE, 2), cmd    # before: to facade fire 33, floor 1
    # no search owed there (searched twice, no misplaced fire): the fires elsewhere come first
    s2 = Strategy()
    for floor in (0, 1, 2):
        s2.book.facade_searches[floor] = 2
    s2.on_sent(transit)
    s2.on_result(transit, True, {})
    fires[2].status = C.STATUS_EXTINGUISHED
    [cmd] = s2.decide(world)
    assert cmd.task != C.SEARCH_FACADE and cmd.target == ("transit", 1), cmd


def test_a_robot_a_restarted_central_unit_saw_only_landed_and_now_uninitialized_has_crashed():
    """central_unit.test under load: the central unit restarted as UAV 3 went home (its go_home_and_refill
    ended in the gap), so the new one saw it only landed; UAV 3 then fell back to UNINITIALIZED (the
    simulator's crash state) and was never judged crashed: 'the crashed UAV's regions were not freed'. Seen
    ready, then UNINITIALIZED for CRASH_CONFIRM_S: crashed. A respawned agent's UNINITIALIZED until it hears
    its UAL (ual/state at least every 1 s), shorter: not."""
    from mbzirc_central_unit.bookkeeping import CRASH_CONFIRM_S
    s = Strategy()                                  # the restarted node: it never saw anybody fly

    def uav3(t, state):
        a = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, 0.0, 3.3, 0.0, ual_state=state, water_level=2.0,
                      last_seen=t)
        return s.decide(WorldView(t, {"3": a}, {}))
    uav3(0.0, C.UAL_LANDED_ARMED)
    uav3(1.0, C.UAL_UNINITIALIZED)                  # a respawned agent, not yet hearing its UAL
    uav3(1.0 + CRASH_CONFIRM_S - 0.5, C.UAL_UNINITIALIZED)
    uav3(1.0 + CRASH_CONFIRM_S - 0.4, C.UAL_LANDED_ARMED)
    assert not s.crashed
    uav3(10.0, C.UAL_UNINITIALIZED)                 # crashed
    assert not s.crashed                            # not at once
    cmds = uav3(10.0 + CRASH_CONFIRM_S, C.UAL_UNINITIALIZED)
    assert "3" in s.crashed and s.broken("3") and not cmds


def test_realistic_111_a_facade_fire_estimated_nearer_the_face_the_extension_hides_is_watered_from_its_holder():
    """Realistic seed 111: facade fire A_4 (23.7, 19.5, 0.75; facade A, 0.5 m from the tower's east corner)
    estimated 1.8 m into the tower, nearer its east face, which the extension hides below 4.5 m: the
    viewpoint went 2 m east of that, inside the extension, every transit to it was refused ('inside the
    building outline') and the fire was never watered. The viewpoint is now on the nearest facade whose
    viewpoint is open at that height, out from the facade's known plane (not from the estimate: 1.8 m inside,
    its viewpoint would stand 0.2 m from the wall)."""
    s = Strategy(StrategyParams())
    a = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, 30.0, 25.0, 1.5, ual_state=C.UAL_FLYING_AUTO,
                  water_level=2.0, last_seen=0.0)
    fire = FireView(7, 23.9, 17.9, 0.8, C.KIND_FACADE)
    cmd = s.water._facade_step(a, 0, fire)
    assert cmd.task == C.FOLLOW_PATH, cmd
    end = cmd.goal["path"][-1]
    assert end[:2] == pytest.approx((23.9, 19.5 + C.FACADE_STANDOFF)), end   # in front of facade A (A_4's)
    for p in cmd.goal["path"]:
        assert not any(b[0] < p[0] < b[2] and b[1] < p[1] < b[3] for b in c3.FOOTPRINTS), p


def test_realistic_106_a_uav_left_hovering_low_over_its_pad_is_sent_home_directly():
    """Realistic seed 106: UAV 3's landing failed 1 m over its pad (0, 3.3); sent 'leaving the building' to
    climb to 12 m at an elevator, its go-to and UAV 2's way home waited for each other's regions for the rest
    of the trial. Over its own pad a UAV gets go_home_and_refill at once; farther off, the transit as before."""
    s = Strategy(StrategyParams())

    def uav3(x, y, z):
        return AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, x, y, z, ual_state=C.UAL_FLYING_AUTO,
                         water_level=0.0, last_seen=0.0)
    assert s.router.go_home(uav3(0.6, 3.8, 1.0), "refill").task == C.GO_HOME_AND_REFILL
    assert s.router.go_home(uav3(-6.0, 10.0, 1.0), "refill").task == C.FOLLOW_PATH


def test_realistic_101_a_uav_just_in_through_the_window_that_reaches_a_fire_waters_it_from_there():
    """Realistic seed 101 (final-commit benchmark): in2_e (17.9, 16.5, 11.5, on the east face of an interior
    wall) estimated at (16.5, 16.75), 1.4 m through that wall; found from room 1 (east), whose window is the
    way to it, but no viewpoint of it is in clear line from inside room 1. Before: UAV 3 was sent in through
    room 1's window, then at once out through it to reach room 1, and in again, for 600 s; the fire was left at
    58 %. Now, just in through that window, it is watered from there."""
    s = Strategy(StrategyParams())
    found = Command("2", C.SEARCH_INDOOR, {"floor": 2, "path": []}, "searching floor 2 indoors (room 1)", (2, 1))
    s.on_sent(found)
    s.on_result(found, True, {"fire_ids": [19]}, now=0.0)
    s.book.pending_ids.clear()
    fire = FireView(19, 16.5, 16.75, 11.98, C.KIND_INDOOR)

    def uav3(t, x, y):
        a = AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, x, y, 12.5, ual_state=C.UAL_FLYING_AUTO,
                      water_level=2.0, last_seen=t)
        return s.decide(WorldView(t, {"3": a}, {19: fire}))
    [enter] = uav3(0.0, 20.0, 21.5)                                  # in front of room 1's window
    assert (enter.task, enter.target) == (C.ENTER_BUILDING, (2, 1)), enter
    s.on_sent(enter)
    s.on_result(enter, True, {}, now=1.0)
    [cmd] = uav3(2.0, 20.0, 18.8)                                    # inside room 1
    assert cmd.task == C.EXTINGUISH_INDOOR_FIRE and cmd.goal["fire_id"] == 19, cmd
