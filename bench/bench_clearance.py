#!/usr/bin/env python3
"""Benchmark of the UAVs' clearance guard: how often a UAV holding in front of the lowest facade holder
(A_4, 0.75 m up) touches the ground with the realistic GNSS error, with and without the guard.

No ROS: ual_sim's Simulation (library, `realistic` profile, no wind) steps the physics; the agents'
ClearanceKeeper (the code the UAV agent runs) reads the simulated altimeter and reported pose and sends its
go-tos to the simulated UAL. Per trial (seed 1..N): UAV 2 flying 2 m up at the A_4 standoff, the task's
go-to to the hole's height (0.75 m, in the GNSS frame as every robot command), then a hold of --hold s while
the GNSS error wanders. Three arms on the same seeds (the same GNSS error paths: nothing else draws from
the uncertainty's generator here): no guard (`clearance_guard: false`), the guard, and the guard with a
dead altimeter (NaN readings: its GNSS fallback). Figures: trials with a ground contact (ual_sim's crash
"hit the ground", or "left the arena" through the arena's floor), other crashes, the lowest true height, the share of held time below the 0.5 m clearance, the mean
true height (the hole is at 0.75 m: how far from it the camera loop would have to bring the nozzle).
    python bench/bench_clearance.py [--trials 40] [--hold 90]
Writes bench/results/clearance.json.
"""
from __future__ import annotations

import argparse
import math
import time
from types import SimpleNamespace

import numpy as np

from _common import load_averages, use_sources, write_result

use_sources("ual_sim/src", "mbzirc_arena/src")

A4_STANDOFF = (23.7, 22.0, -math.pi / 2)     # x, y, yaw 2.5 m in front of holder A_4 (facade A faces +y):
#                                               off the wall by more than the horizontal GNSS error
HOLE_Z = 0.75
DT = 1.0 / 30.0


class SimAgent:
    """What ClearanceKeeper reads of a UavAgent, served by the library simulation."""

    def __init__(self, sim, rid: int, params: dict):
        from mbzirc_agents.params import AgentParams
        self.p = AgentParams.from_dict(params)
        self.arena = list(self.p.arena)
        self.r = sim.robots[rid]
        self.iface = SimpleNamespace(add_subscriber=lambda *args: None)
        quiet = lambda *args: None  # noqa: E731
        self.backend = SimpleNamespace(now=lambda: sim.time, loginfo_throttle=quiet, logerr_throttle=quiet)
        self.pose = None

    @property
    def ual_state(self) -> int:
        return self.r.state

    def pose_in_doubt(self) -> bool:
        return False

    def position(self, wait: float = 0.0) -> np.ndarray:
        return self.pose.copy()

    def pose_at(self, stamp: float) -> np.ndarray:
        return self.pose.copy()


def trial(seed: int, arm: str, hold: float) -> dict:
    """One hold in front of A_4; returns the ground contact and the true heights."""
    import rospy
    from sensor_msgs.msg import Range
    from mbzirc_agents.clearance_keeper import ClearanceKeeper
    from ual_sim import constants as SC
    from ual_sim.sim import Simulation
    from ual_sim.uncertainty import profile
    from ual_sim.world import load_world

    world = load_world()
    sim = Simulation(world, seed=seed, uncertainty=profile(world.uncertainty, "realistic"), wind=False)
    r = sim.robots[2]
    x, y, yaw = A4_STANDOFF
    r.pos[:] = (x, y, 2.0)
    r.yaw = yaw
    r.goal = r.pos.copy()
    r.state, r.mode = SC.FLYING_AUTO, "idle"
    agent = SimAgent(sim, 2, {"clearance_guard": arm != "no guard"})
    keeper = ClearanceKeeper(agent, lambda gx, gy, gz, gyaw: r.go_to(gx, gy, gz, gyaw))
    heights = []
    for k in range(int(round((hold + 5.0) / DT))):
        z_before = r.pos[2]
        sim.step(DT)
        agent.pose = np.array(sim.reported_pose(r))
        if k % 3 == 0:                                            # altimeter ~10 Hz here (20 Hz in the node)
            m = Range()
            m.header.stamp = rospy.Time.from_sec(sim.time)
            m.range = math.nan if arm == "guard, dead altimeter" else sim.altimeter(r)
            keeper._on_range(m)
            keeper.step()                                          # the keeper's watch, 10 Hz
        if k == 30:                                                # the task's go-to, once the guard has data
            keeper.waypoint(x, y, HOLE_Z, yaw)
        if k > 30 + 5.0 / DT:                                      # held (5 s to get there)
            heights.append(r.pos[2])
        if r.crashed:
            break
    # ground contact: ual_sim's "hit the ground", or "left the arena" through its floor (z < 0)
    contact = r.crashed and (r.crash_reason == "hit the ground"
                             or (r.crash_reason == "left the arena" and z_before < 0.05))
    h = np.array(heights) if heights else np.array([r.pos[2]])
    return {"contact": contact, "other_crash": r.crashed and not contact, "min_z": float(h.min()),
            "below_clearance": float(np.mean(h < 0.5)), "mean_z": float(h.mean())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--hold", type=float, default=90.0, help="s held after reaching the set-point")
    a = ap.parse_args()
    arms = ["no guard", "guard", "guard, dead altimeter"]
    t0 = time.monotonic()
    out = {"trials": a.trials, "hold_s": a.hold, "load_average": load_averages(), "arms": {}}
    for arm in arms:
        rows = [trial(seed, arm, a.hold) for seed in range(1, a.trials + 1)]
        fig = {"ground_contacts": int(sum(bool(r["contact"]) for r in rows)),
               "other_crashes": int(sum(bool(r["other_crash"]) for r in rows)),
               "lowest_true_z_m": round(min(r["min_z"] for r in rows), 3),
               "held_time_below_0.5m": round(float(np.mean([r["below_clearance"] for r in rows])), 4),
               "mean_true_z_m": round(float(np.mean([r["mean_z"] for r in rows])), 3)}
        out["arms"][arm] = fig
        print(f"{arm:24s} ground contacts {fig['ground_contacts']:3d}/{a.trials} (other crashes "
              f"{fig['other_crashes']}), lowest true z "
              f"{fig['lowest_true_z_m']:+.2f} m, held time below 0.5 m {100 * fig['held_time_below_0.5m']:.1f} %, "
              f"mean true z {fig['mean_true_z_m']:.2f} m")
    out["wall_s"] = round(time.monotonic() - t0, 1)
    write_result("clearance", out)


if __name__ == "__main__":
    main()
