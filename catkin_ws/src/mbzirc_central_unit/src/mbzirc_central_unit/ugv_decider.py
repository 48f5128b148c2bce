"""The UGV's decisions: it searches the ground floor indoors through the door and puts out what it finds."""
from __future__ import annotations

from typing import Optional

from . import constants as C
from .command import Command
from .decider import Decider
from .transit import nearest
from .world_model import AgentView, WorldView

DOOR = (0, "door")  # the UGV's indoor search target: the ground floor through the door


class UgvDecider(Decider):
    def decide(self, a: AgentView, world: WorldView) -> Optional[Command]:
        fires = world.fires_of(C.KIND_INDOOR, 0)
        if fires and a.water_level > 0.05:  # the UGV cannot refill: it uses every drop
            f = nearest(a, fires)
            if self.book.ok(a, C.EXTINGUISH_INDOOR_FIRE, f.fire_id):
                return Command(a.agent_id, C.EXTINGUISH_INDOOR_FIRE, {"fire_id": f.fire_id},
                               f"indoor fire {f.fire_id} on the ground floor", f.fire_id)
        if not world.extinguished_on(C.KIND_INDOOR, 0) and self.book.indoor_searches[DOOR] < self.p.facade_searches \
                and self.book.ok(a, C.SEARCH_INDOOR, DOOR):
            return Command(a.agent_id, C.SEARCH_INDOOR, {"floor": 0, "path": list(self.p.ugv_indoor_path)},
                           "ground floor through the door", DOOR)
        return None

    def work_left(self, world: WorldView) -> bool:
        return not world.extinguished_on(C.KIND_INDOOR, 0) and self.book.indoor_searches[DOOR] < 2
