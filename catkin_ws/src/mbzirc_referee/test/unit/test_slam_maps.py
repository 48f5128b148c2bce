"""SLAM floor maps: grids checked, placed in the arena frame with their anchor, merged, written in map_server's
format and read back the way map_server reads them."""
import math

import numpy as np
import pytest

from mbzirc_referee.slam_maps import (FREE, OCCUPIED, UNKNOWN, Grid, GridError, grid_from_message, map_entry,
                                      place, read_map_server, trinary, write_map_server)


def grid(width=20, height=10, res=0.1, origin=(0.0, 0.0, 0.0), fill=-1):
    return Grid(np.full((height, width), fill, dtype=np.int8), res, origin)


def code_at(m, x, y):
    """The code of the placed map's cell that holds arena point (x, y)."""
    col = int(math.floor((x - m.origin[0]) / m.resolution))
    row = int(math.floor((y - m.origin[1]) / m.resolution))
    return int(m.codes[row, col])


@pytest.mark.parametrize("args,why", [
    ((4, 3, 0.05, (0, 0, 0), [0] * 11), "data has 11 cells, 4x3"),
    ((4, 3, math.nan, (0, 0, 0), [0] * 12), "resolution"),
    ((4, 3, 0.0, (0, 0, 0), [0] * 12), "resolution"),
    ((0, 3, 0.05, (0, 0, 0), []), "empty grid"),
    ((4, 3, 0.05, (0, math.inf, 0), [0] * 12), "origin"),
    ((5000, 5000, 0.05, (0, 0, 0), b""), "larger than"),
])
def test_a_malformed_grid_is_refused_with_its_reason(args, why):
    with pytest.raises(GridError, match=why):
        grid_from_message(*args)


def test_a_well_formed_grid_keeps_rows_from_the_origin():
    g = grid_from_message(3, 2, 0.05, (1.0, 2.0, 0.5), bytes([0, 100, 255, 0, 0, 0]))
    assert g.cells.shape == (2, 3) and g.cells[0, 1] == 100 and g.cells[0, 2] == -1
    assert g.origin == (1.0, 2.0, 0.5) and g.resolution == 0.05


def test_trinary_uses_the_yaml_thresholds():
    codes = trinary(np.array([-1, 0, 19, 20, 64, 65, 100, 101, -50], dtype=np.int16))
    assert list(codes) == [UNKNOWN, FREE, FREE, UNKNOWN, UNKNOWN, OCCUPIED, OCCUPIED, UNKNOWN, UNKNOWN]


def test_a_grid_is_placed_by_its_anchor_and_origin():
    g = grid(origin=(1.0, 2.0, 0.0))
    g.cells[3:7, 2:18] = 0             # free room
    g.cells[5, 10] = 100               # one wall cell: centre (2.05, 2.55) in the map frame
    m = place([(g, (10.0, 20.0, 0.0))])
    assert m.resolution == pytest.approx(0.1)
    assert m.origin == pytest.approx((10.0 + 1.0 + 0.2, 20.0 + 2.0 + 0.3))     # the known cells' corner
    assert m.codes.shape == (4, 16)
    assert code_at(m, 12.05, 22.55) == OCCUPIED
    assert code_at(m, 11.25, 22.35) == FREE
    assert m.count(OCCUPIED) == 1 and m.count(FREE) == 4 * 16 - 1


def test_a_rotated_anchor_turns_the_map():
    g = grid(width=40, height=40, res=0.1)
    g.cells[20, 0:40] = 100            # a wall along the map's x axis at map y = 2.05
    g.cells[0:20, 0:40] = 0            # free on its -y side
    m = place([(g, (5.0, 5.0, math.pi / 2))])
    # map (x, y) -> arena (5 - y, 5 + x): the wall runs along arena y at x = 2.95, free at x > 2.95
    for ay in (5.2, 6.5, 8.8):
        assert code_at(m, 2.95, ay) == OCCUPIED
        assert code_at(m, 4.0, ay) == FREE
    assert m.extent[0] == pytest.approx(2.9, abs=1e-6) and m.extent[1] == pytest.approx(5.0, abs=1e-6)


def test_a_wall_turned_by_an_odd_angle_keeps_no_gaps():
    g = grid(width=100, height=20, res=0.05)
    g.cells[10, :] = 100
    m = place([(g, (0.0, 0.0, 0.5))])
    # the placed cell under every wall cell's centre is occupied (sampling alone leaves holes in such a line)
    for i in range(100):
        lx, ly = (i + 0.5) * 0.05, 10.5 * 0.05
        x, y = math.cos(0.5) * lx - math.sin(0.5) * ly, math.sin(0.5) * lx + math.cos(0.5) * ly
        assert code_at(m, x, y) == OCCUPIED, i


def test_merging_occupied_wins_over_free_and_free_over_unknown():
    a, b = grid(), grid()
    a.cells[0:5, :] = 0                # a: free lower half
    b.cells[2, 4] = 100                # b: a wall inside a's free half ...
    b.cells[7, 4] = 0                  # ... and a free cell where a knows nothing
    m = place([(a, (0.0, 0.0, 0.0)), (b, (0.0, 0.0, 0.0))])
    assert code_at(m, 0.45, 0.25) == OCCUPIED
    assert code_at(m, 0.45, 0.75) == FREE
    assert code_at(m, 0.95, 0.75) == UNKNOWN
    assert code_at(m, 1.55, 0.15) == FREE
    # the same with the grids the other way round
    m2 = place([(b, (0.0, 0.0, 0.0)), (a, (0.0, 0.0, 0.0))])
    assert np.array_equal(m.codes, m2.codes)


def test_nothing_known_is_no_map():
    assert place([(grid(), (0.0, 0.0, 0.0))]) is None and place([]) is None


def test_files_are_map_savers_format_and_read_back_the_same(tmp_path):
    g = grid(width=30, height=12, res=0.05, origin=(-1.0, -0.5, 0.0))
    g.cells[:, :] = 0
    g.cells[11, :] = 100               # top row of the map: the first row of the image
    g.cells[0, 3] = -1
    m = place([(g, (3.0, 4.0, 0.0))])
    path = write_map_server(m, str(tmp_path), "map_floor1")
    text = (tmp_path / "map_floor1.yaml").read_text()
    for line in ("image: map_floor1.pgm", "negate: 0", "occupied_thresh: 0.65", "free_thresh: 0.196",
                 "resolution: 0.050000", "origin: [2.000000, 3.500000, 0.000000]"):
        assert line in text
    raw = (tmp_path / "map_floor1.pgm").read_bytes()
    assert raw.startswith(b"P5\n# CREATOR: ")
    pixels = raw[-30 * 12:]
    assert set(pixels[:30]) == {0}                     # the wall row (largest y) comes first
    assert pixels[-30 + 3] == 205 and pixels[-30] == 254
    back = read_map_server(path)
    assert np.array_equal(back.codes, m.codes)
    assert back.resolution == pytest.approx(0.05) and back.origin == pytest.approx(m.origin)


def test_map_entry_counts_cells_and_names_files():
    g = grid()
    g.cells[0, 0:3] = 100
    g.cells[1, 0:3] = 0
    e = map_entry(2, ["0", "3"], "map_floor2", place([(g, (0.0, 0.0, 0.0))]))
    assert e["floor"] == 2 and e["robots"] == ["0", "3"] and e["yaml"] == "map_floor2.yaml"
    assert e["image"] == "map_floor2.pgm" and e["size"] == [3, 2]
    assert e["occupied_cells"] == 3 and e["free_cells"] == 3


def test_sampling_in_bands_gives_the_same_map(monkeypatch):
    from mbzirc_referee import slam_maps
    g = grid(width=30, height=25, res=0.1)
    g.cells[5:20, 3:27] = 0
    g.cells[12, 3:27] = 100
    whole = place([(g, (1.0, 2.0, 0.7))])
    monkeypatch.setattr(slam_maps, "BAND_ROWS", 4)
    assert np.array_equal(place([(g, (1.0, 2.0, 0.7))]).codes, whole.codes) and whole.codes.shape[0] > 8
