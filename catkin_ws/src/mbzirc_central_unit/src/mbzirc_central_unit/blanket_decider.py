"""The blanket UAV's decisions: it visits the outdoor fire holders (then sweeps the open area), covers a
ground fire, gets a new blanket at home, and repeats until the ground fires are out."""
from __future__ import annotations

from typing import Optional

from . import constants as C
from . import geometry as G
from .command import Command
from .decider import Decider
from .transit import nearest
from .world_model import AgentView, WorldView

# The blanket UAV's searches in turn: the known outdoor holders (quick), then a sweep of the open area.
GROUND_SEARCH_PLAN = ("holders", "holders", "sweep", "holders", "sweep")


class BlanketDecider(Decider):
    def work_left(self, world: WorldView) -> bool:
        out = sum(1 for f in world.fires_of(C.KIND_GROUND, actionable=False) if f.extinguished)
        if out >= self.p.num_ground_fires:
            return False
        return bool(world.fires_of(C.KIND_GROUND)) or self.book.ground_searches < len(GROUND_SEARCH_PLAN)

    def decide(self, a: AgentView, world: WorldView) -> Optional[Command]:
        if not self.work_left(world):
            return self.router.go_home_for_good(a)
        if not a.has_blanket:
            if not self.book.ok(a, C.GO_HOME_AND_REFILL, None):
                return None  # the resets keep failing: nothing more this robot can do
            return Command(a.agent_id, C.GO_HOME_AND_REFILL, {}, "new blanket", None)
        if a.landed:
            return Command(a.agent_id, C.TAKE_OFF, {"height": self.router.altitude(a.agent_id)},
                           "to search the ground")
        fires = [f for f in world.fires_of(C.KIND_GROUND) if self.book.ok(a, C.EXTINGUISH_GROUND_FIRE, f.fire_id)]
        if fires:
            f = nearest(a, fires)
            return Command(a.agent_id, C.EXTINGUISH_GROUND_FIRE, {"fire_id": f.fire_id},
                           f"blanket on ground fire {f.fire_id}", f.fire_id)
        alt = self.router.altitude(a.agent_id)
        if GROUND_SEARCH_PLAN[min(self.book.ground_searches, len(GROUND_SEARCH_PLAN) - 1)] == "holders":
            path = G.ground_search_path(a.position, alt, self.p.layout.ground_holders)
            return Command(a.agent_id, C.LOOK_FOR_GROUND_FIRES, {"path": path}, "outdoor fire holders",
                           "holders")
        path = G.lawnmower_path(altitude=alt)
        return Command(a.agent_id, C.LOOK_FOR_GROUND_FIRES, {"path": path}, "sweep of the open area", "sweep")
