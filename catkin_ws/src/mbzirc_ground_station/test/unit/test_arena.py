"""The page's arena: the team's public model (mbzirc_arena), never the simulator's private world."""
import os

import pytest

from mbzirc_arena.c3 import ARENA
from mbzirc_ground_station.arena import ArenaError, load_arena, page_arena

WORLD = os.path.join(os.path.dirname(__file__), "..", "..", "..", "ual_sim", "src", "ual_sim", "worlds",
                     "c3_default.yaml")


def test_the_default_arena_is_drawn_from_the_team_model():
    a = load_arena("")
    assert a["floors"] == list(ARENA.floor_heights)
    assert len(a["facade_holders"]) == len(ARENA.facade_holders) == 15
    assert {h["id"] for h in a["homes"]} == {"0", "1", "2", "3"}
    openings = [o for w in a["walls"] for o in w["openings"]]
    assert len(openings) == len(ARENA.openings) and any(o["door"] for o in openings)


def test_no_private_fact_reaches_the_page():
    """Interior walls and indoor holders are the simulator's (robots must sense them): the page drew them."""
    a = load_arena(WORLD)
    assert not any(w["inner"] for w in a["walls"])
    assert "indoor_holders" not in a and "active" not in a
    assert a == page_arena(ARENA, a["name"]) or a["facade_holders"] == load_arena("")["facade_holders"]


def test_a_window_is_a_segment_across_its_wall_normal():
    a = page_arena(ARENA)
    for w in a["walls"]:
        for o in w["openings"]:
            x0, y0, x1, y1 = o["seg"]
            assert (x0 == pytest.approx(x1)) != (y0 == pytest.approx(y1))   # along one axis only


def test_an_unreadable_world_file_is_a_clear_error(tmp_path):
    bad = tmp_path / "w.yaml"
    bad.write_text("arena: [1, 2")
    with pytest.raises(ArenaError, match="cannot read world file"):
        load_arena(str(bad))
