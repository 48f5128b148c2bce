"""GridLevel: ray updates (Bresenham, once per scan, endpoint wins) and bilinear access with gradient."""
import numpy as np
import pytest

from hector_mapping.grid import GridLevel, logit


def make(size=64, res=0.1):
    # corner so that world (0, 0) is the centre of cell (32, 32)
    return GridLevel(size, res, (-(size // 2) * res - res / 2, -(size // 2) * res - res / 2))


def reference_ray(o, e):
    """Per-beam loop Bresenham between integer cells (origin included, end excluded, half up)."""
    d = (e[0] - o[0], e[1] - o[1])
    n = max(abs(d[0]), abs(d[1]))
    cells = []
    for t in range(n):
        if abs(d[0]) >= abs(d[1]):
            cells.append((o[0] + t * np.sign(d[0]), o[1] + int(np.floor(t * d[1] / n + 0.5))))
        else:
            cells.append((o[0] + int(np.floor(t * d[0] / n + 0.5)), o[1] + t * np.sign(d[1])))
    return cells


def test_logit_of_update_factors():
    assert logit(0.4) == pytest.approx(-0.405, abs=1e-3)
    assert logit(0.9) == pytest.approx(2.197, abs=1e-3)


def test_single_beam_marks_free_cells_then_the_endpoint():
    g = make()
    g.update(np.array([0.0, 0.0]), np.array([[1.0, 0.0]]))
    row = g.log_odds[32]
    assert np.allclose(row[32:42], logit(0.4))
    assert row[42] == pytest.approx(logit(0.9))
    assert row[43] == 0.0 and row[31] == 0.0
    assert g.known[32, 32:43].all() and not g.known[33].any()
    assert g.prob[32, 42] == pytest.approx(0.9, abs=1e-6)


def test_vectorised_rays_equal_a_per_beam_bresenham():
    g = make(size=200, res=0.05)
    rng = np.random.default_rng(3)
    ends = rng.uniform(-4.5, 4.5, (300, 2))
    origin = np.array([0.013, -0.021])
    free, occ = g.ray_cells(origin, ends)
    o = np.rint(g.world_to_map(origin[None]))[0].astype(int)
    e = np.rint(g.world_to_map(ends)).astype(int)
    expected = set()
    for ei in e:
        expected.update(reference_ray(tuple(o), tuple(ei)))
    got = {(int(f % g.size), int(f // g.size)) for f in free}
    assert got == expected
    assert set(occ.tolist()) == {int(y * g.size + x) for x, y in e}


def test_each_cell_changes_once_per_scan_and_endpoint_wins():
    g = make()
    # 50 identical beams: still one free update per cell and one occupied update at the end.
    g.update(np.zeros(2), np.tile([[1.0, 0.0]], (50, 1)))
    assert g.log_odds[32, 35] == pytest.approx(logit(0.4))
    assert g.log_odds[32, 42] == pytest.approx(logit(0.9))
    # One beam ends at x=0.5 (cell 37) while another passes through it: the endpoint wins.
    g2 = make()
    g2.update(np.zeros(2), np.array([[1.0, 0.0], [0.5, 0.0]]))
    assert g2.log_odds[32, 37] == pytest.approx(logit(0.9))
    assert g2.log_odds[32, 36] == pytest.approx(logit(0.4))


def test_log_odds_accumulate_over_scans_and_are_clamped():
    g = make()
    for _ in range(3):
        g.update(np.zeros(2), np.array([[1.0, 0.0]]))
    assert g.log_odds[32, 42] == pytest.approx(3 * logit(0.9), rel=1e-5)
    for _ in range(40):
        g.update(np.zeros(2), np.array([[1.0, 0.0]]))
    assert g.log_odds[32, 42] <= 50.0


def test_beams_leaving_the_grid_and_origin_outside_are_dropped():
    g = make()
    assert g.update(np.zeros(2), np.array([[100.0, 0.0], [1.0, 0.0]])) == 1
    g2 = make()
    assert g2.update(np.array([100.0, 0.0]), np.array([[1.0, 0.0]])) == 0
    assert not g2.known.any()


def test_interpolation_hits_cell_values_at_centres_and_gradient_is_exact():
    g = make(size=32, res=0.1)
    rng = np.random.default_rng(0)
    g.prob[:] = rng.uniform(0, 1, g.prob.shape).astype(np.float32)
    centres = g.map_to_world(np.array([[5.0, 7.0], [20.0, 3.0]]))
    m, _, _ = g.interpolate(centres)
    assert m == pytest.approx([g.prob[7, 5], g.prob[3, 20]], abs=1e-6)
    # Inside a cell the bilinear surface is smooth: finite differences must equal the gradient.
    pts = g.map_to_world(rng.uniform(2.1, 28.9, (200, 2)))
    frac = g.world_to_map(pts) % 1.0
    pts = pts[np.all((frac > 0.01) & (frac < 0.99), axis=1)]
    m, gx, gy = g.interpolate(pts)
    h = 1e-5
    fx = (g.interpolate(pts + [h, 0])[0] - g.interpolate(pts - [h, 0])[0]) / (2 * h)
    fy = (g.interpolate(pts + [0, h])[0] - g.interpolate(pts - [0, h])[0]) / (2 * h)
    assert gx == pytest.approx(fx, abs=1e-3)
    assert gy == pytest.approx(fy, abs=1e-3)


def test_points_outside_the_grid_give_zero():
    g = make(size=16)
    g.prob[:] = 0.7
    m, gx, gy = g.interpolate(np.array([[50.0, 0.0], [0.0, -50.0]]))
    assert np.all(m == 0) and np.all(gx == 0) and np.all(gy == 0)


def test_occupancy_grid_values():
    g = make()
    g.update(np.zeros(2), np.array([[1.0, 0.0]]))
    data = g.occupancy_grid_data()
    assert data[32, 42] == 100 and data[32, 35] == 0 and data[0, 0] == -1
    g.reset()
    assert (g.occupancy_grid_data() == -1).all() and (g.prob == 0.5).all()


def test_the_known_box_holds_every_touched_cell_and_crops_the_grid_to_them():
    """map_pub_known_area: the published grid is the box of the cells scans touched, found without a pass
    over the whole grid; the cropped data is the whole grid's in that box and nothing known lies outside."""
    g = make()
    assert g.known_bounds() is None
    rng = np.random.default_rng(3)
    for origin in ((0.0, 0.0), (1.2, -0.7)):
        angles = rng.uniform(-np.pi, np.pi, 40)
        ranges = rng.uniform(0.3, 2.5, 40)
        g.update(np.array(origin), np.c_[origin[0] + ranges * np.cos(angles), origin[1] + ranges * np.sin(angles)])
    box = g.known_bounds()
    rows, cols = np.nonzero(g.known)
    assert box == (cols.min(), rows.min(), cols.max(), rows.max())
    full = g.occupancy_grid_data()
    crop = g.occupancy_grid_data(box)
    assert crop.shape == (box[3] - box[1] + 1, box[2] - box[0] + 1)
    assert (crop == full[box[1]:box[3] + 1, box[0]:box[2] + 1]).all()
    g.reset()
    assert g.known_bounds() is None
