"""A toy executor for the strategy: every command completes at once with a plausible effect.

It lets the unit tests play whole missions through `Strategy` without ROS: which fires are found depends
only on where the robots searched, and water runs out, so the refill and reassignment logic is exercised.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from mbzirc_central_unit import constants as C
from mbzirc_central_unit import geometry as G
from mbzirc_central_unit.strategy import Command, Strategy
from mbzirc_central_unit.world_model import AgentView, FireView, WorldView

HOMES = {"0": (5.0, 10.0, 0.0), "1": (-2.0, 1.65, 0.0), "2": (0.0, 0.0, 0.0), "3": (0.0, 3.3, 0.0)}
TRUE_FIRES = {  # id: (kind, position, litres needed)
    1: (C.KIND_GROUND, (1.0, 14.0, 0.0), 0.0), 2: (C.KIND_GROUND, (-9.0, 20.0, 0.0), 0.0),
    3: (C.KIND_FACADE, (23.7, 19.5, 0.75), 2.5), 4: (C.KIND_FACADE, (24.2, 8.2, 8.25), 1.5),
    5: (C.KIND_FACADE, (11.4, 14.5, 10.5), 1.5),
    6: (C.KIND_INDOOR, (17.7, 8.5, 1.5), 1.0), 7: (C.KIND_INDOOR, (17.9, 16.5, 6.5), 1.0),
    8: (C.KIND_INDOOR, (17.7, 8.5, 11.5), 1.0),
}
TANK = 2.0


@dataclass
class FakeMission:
    """Agents, fires and a clock; `step()` asks the strategy and applies its commands."""
    strategy: Strategy = field(default_factory=Strategy)
    now: float = 0.0
    agents: dict = field(default_factory=dict)
    fires: dict = field(default_factory=dict)
    water_in: dict = field(default_factory=dict)
    log: list = field(default_factory=list)
    now_of: list = field(default_factory=list)   # sim time of each log entry
    silent: set = field(default_factory=set)
    fail_tasks: set = field(default_factory=set)  # (agent, task) that always abort

    def __post_init__(self):
        if not self.agents:
            self.agents = {
                "0": AgentView("0", C.ROBOT_UGV, C.PAYLOAD_WATER, *HOMES["0"], ual_state=C.UAL_LANDED_ARMED,
                               water_level=TANK),
                "1": AgentView("1", C.ROBOT_UAV, C.PAYLOAD_BLANKET, *HOMES["1"], ual_state=C.UAL_LANDED_ARMED,
                               has_blanket=True),
                "2": AgentView("2", C.ROBOT_UAV, C.PAYLOAD_WATER, *HOMES["2"], ual_state=C.UAL_LANDED_ARMED,
                               water_level=TANK),
                "3": AgentView("3", C.ROBOT_UAV, C.PAYLOAD_WATER, *HOMES["3"], ual_state=C.UAL_LANDED_ARMED,
                               water_level=TANK),
            }

    def world(self) -> WorldView:
        for a in self.agents.values():
            if a.agent_id not in self.silent:
                a.last_seen = self.now
        return WorldView(self.now, dict(self.agents), dict(self.fires))

    def reveal(self, fid: int) -> None:
        kind, pos, _ = TRUE_FIRES[fid]
        if fid not in self.fires:
            self.fires[fid] = FireView(fid, *pos, kind=kind, status=C.STATUS_ACTIVE)

    def step(self) -> list[Command]:
        self.now += 10.0
        cmds = self.strategy.decide(self.world())
        for cmd in cmds:
            self.strategy.on_sent(cmd)
            ok, result = self.apply(cmd)
            self.log.append((cmd, ok))
            self.now_of.append(self.now)
            self.strategy.on_result(cmd, ok, result, self.now)
        return cmds

    def all_out(self) -> bool:
        return all(fid in self.fires and self.fires[fid].extinguished for fid in TRUE_FIRES)

    def run(self, max_steps: int = 300) -> int:
        for i in range(max_steps):
            self.step()
            if self.all_out():
                return i + 1
        return -1

    def apply(self, cmd: Command):
        a = self.agents[cmd.agent_id]
        g = cmd.goal
        if (cmd.agent_id, cmd.task) in self.fail_tasks:
            return False, {"message": "forced failure"}
        t = cmd.task
        if t == C.TAKE_OFF:
            a.z, a.ual_state = g["height"], C.UAL_FLYING_AUTO
        elif t in (C.FOLLOW_PATH, C.SEARCH_FACADE, C.LOOK_FOR_GROUND_FIRES) and g.get("path") and a.is_uav:
            a.x, a.y, a.z = g["path"][-1][:3]
        elif t == C.SEARCH_INDOOR and g.get("path") and a.is_uav:
            # Like the agents (~stop_at_first_fire): stop at the first waypoint once a fire of the floor
            # is known.
            known = any(f.kind == C.KIND_INDOOR and f.floor == g["floor"] and not f.extinguished
                        for f in self.fires.values())
            a.x, a.y, a.z = g["path"][0 if known else -1][:3]
        if t == C.SEARCH_FACADE:
            for fid, (kind, pos, _) in TRUE_FIRES.items():
                if kind == C.KIND_FACADE and G.floor_of(pos[2]) == g["floor"]:
                    self.reveal(fid)
        elif t == C.LOOK_FOR_GROUND_FIRES:
            for fid, (kind, pos, _) in TRUE_FIRES.items():
                if kind == C.KIND_GROUND and any(math.dist(p[:2], pos[:2]) < 3 for p in g["path"]):
                    self.reveal(fid)
        elif t == C.SEARCH_INDOOR:
            layout = self.strategy.p.layout
            for fid, (kind, pos, _) in TRUE_FIRES.items():
                if kind != C.KIND_INDOOR or G.floor_of(pos[2]) != g["floor"]:
                    continue
                if not a.is_uav or layout.clear_indoors(g["floor"], a.position, pos) or any(
                        layout.clear_indoors(g["floor"], p[:3], pos) for p in g["path"]):
                    self.reveal(fid)
        elif t == C.ENTER_BUILDING:
            e = g["entry"]
            a.x, a.y, a.z = e[0] + 4.5 * math.cos(e[3]), e[1] + 4.5 * math.sin(e[3]), e[2]
        elif t == C.GO_TO_FACADE_FIRE:
            f = self.fires[g["fire_id"]]
            a.x, a.y, a.z = G.viewpoint(f.position, g["distance"])[:3]
        elif t in (C.EXTINGUISH_FACADE_FIRE, C.EXTINGUISH_INDOOR_FIRE):
            f = self.fires[g["fire_id"]]
            if t == C.EXTINGUISH_FACADE_FIRE and math.dist(a.position, f.position) > 6:
                return False, {"message": "too far"}
            if t == C.EXTINGUISH_INDOOR_FIRE and a.is_uav and (
                    G.floor_of(a.z) != f.floor
                    or not self.strategy.p.layout.clear_indoors(f.floor, a.position, f.position)):
                return False, {"message": "not in the fire's room"}
            need = TRUE_FIRES[f.fire_id][2] - self.water_in.get(f.fire_id, 0.0)
            used = min(need, a.water_level)
            a.water_level -= used
            self.water_in[f.fire_id] = self.water_in.get(f.fire_id, 0.0) + used
            out = self.water_in[f.fire_id] >= TRUE_FIRES[f.fire_id][2] - 1e-9
            if out:
                f.status = C.STATUS_EXTINGUISHED
            return True, {"extinguished": out, "water_left": a.water_level}
        elif t == C.EXTINGUISH_GROUND_FIRE:
            f = self.fires[g["fire_id"]]
            a.has_blanket = False
            f.status = C.STATUS_EXTINGUISHED
            a.x, a.y = f.x, f.y
        elif t == C.GO_HOME_AND_REFILL:
            a.x, a.y, a.z = HOMES[a.agent_id]
            a.ual_state = C.UAL_LANDED_ARMED
            a.has_blanket = a.payload == C.PAYLOAD_BLANKET
            a.water_level = TANK if a.payload == C.PAYLOAD_WATER else 0.0
        return True, {}
