"""SLAM floor maps: grids made compact, anchored in the arena, rate-limited, served apart from the frames."""
import http.client
import json
import math

import pytest
from nav_msgs.msg import OccupancyGrid

from mbzirc_ground_station.floor_maps import FloorMaps, GridError, compact_grid, compose
from mbzirc_ground_station.live import LiveSource
from mbzirc_ground_station.map_adapter import MapListener, map_robot
from mbzirc_ground_station.state import GroundStationState
from mbzirc_ground_station.web import GroundStationServer

from msgs import feed


def test_small_grid_kept_cell_for_cell():
    # 3 x 2, row 0 first: free, occupied, unknown / occupied (100), free (49), occupied (50)
    g = compact_grid(3, 2, 0.05, [0, 100, -1, 100, 49, 50])
    assert g == {"w": 3, "h": 2, "res": 0.05, "cells": "fou" "ofo"}


def test_large_grid_downsampled_by_blocks_walls_survive():
    w, h = 1024, 600
    data = [-1] * (w * h)
    for x in range(w):               # a one-cell wall along row 301
        data[301 * w + x] = 100
    for y in range(0, 8):            # a free patch in the corner
        for x in range(0, 8):
            data[y * w + x] = 0
    g = compact_grid(w, h, 0.05, data, max_side=256)
    assert (g["w"], g["h"]) == (256, 150) and g["res"] == pytest.approx(0.2)
    rows = [g["cells"][i * 256:(i + 1) * 256] for i in range(150)]
    assert rows[75] == "o" * 256                      # cell row 301 // 4
    assert rows[0][:2] == "ff" and rows[0][2] == "u"
    assert set(rows[10]) == {"u"}


def test_grid_not_a_multiple_of_the_factor_pads_with_unknown():
    g = compact_grid(5, 1, 1.0, [100, 0, 0, 0, 0], max_side=2)
    assert (g["w"], g["h"], g["res"], g["cells"]) == (2, 1, 3.0, "of")


def test_bytes_data_read_as_signed():
    g = compact_grid(2, 1, 0.1, bytes([0xff, 100]))
    assert g["cells"] == "uo"


@pytest.mark.parametrize("args", [
    (3, 2, 0.05, [0] * 5),                    # wrong data length
    (3, 2, float("nan"), [0] * 6),            # NaN resolution
    (3, 2, 0.0, [0] * 6),
    (0, 2, 0.05, []),
    (100000, 100000, 0.05, []),               # huge: refused before reading the data
])
def test_malformed_grids_refused(args):
    with pytest.raises(GridError):
        compact_grid(*args)


def test_compose():
    x, y, yaw = compose((10.0, 5.0, math.pi / 2), (2.0, 0.0, 0.1))
    assert (x, y, yaw) == pytest.approx((10.0, 7.0, math.pi / 2 + 0.1))


def test_versions_change_only_with_the_map_and_rate_limit():
    maps = FloorMaps(min_period=3.0)
    g = compact_grid(2, 1, 0.1, [0, 100])
    assert maps.admit("1", 0.0)
    assert maps.update("1", g, (1, 2, 0), 1, "mbzirc2020_1/map", 0.0)
    assert maps.snapshot()["version"] == 1
    assert maps.snapshot(1) == {"version": 1}                 # the page has it: no maps sent
    assert not maps.admit("1", 2.0) and maps.admit("1", 3.0)
    assert not maps.update("1", g, (1, 2, 0), 1, "mbzirc2020_1/map", 3.0)   # the same map: no new version
    assert maps.update("1", g, (1, 2.5, 0), 1, "mbzirc2020_1/map", 6.0)
    assert maps.snapshot(1)["maps"][0]["origin"] == [1, 2.5, 0]
    assert maps.admit("1", 1.0) and maps.snapshot()["maps"] == []           # clock went back: new trial
    with pytest.raises(GridError):
        maps.update("2", g, (float("nan"), 0, 0), 0, "f", 0.0)


def grid_msg(frame="mbzirc2020_1/map", w=4, h=3, res=0.5, data=None, origin=(-1.0, -0.5)):
    m = OccupancyGrid()
    m.header.frame_id = frame
    m.info.width, m.info.height, m.info.resolution = w, h, res
    m.info.origin.position.x, m.info.origin.position.y = origin
    m.info.origin.orientation.w = 1.0
    m.data = data if data is not None else [0, 0, 100, -1] * h
    return m


@pytest.fixture
def node_pieces():
    """The live node's map path: state, FloorMaps, MapListener (TF faked), the HTTP server."""
    state = GroundStationState()
    now = [10.0]
    live = LiveSource(state, lambda: now[0])
    live.apply("/mbzirc2020_1/data_feed", feed("1", 20.0, 10.0, 7.0))    # floor 1 in the C3 arena (5 m slab)
    anchors = {"mbzirc2020_1/map": (20.0, 10.0, math.pi / 2)}
    logged = []
    listener = MapListener(live, FloorMaps(3.0), "arena", lambda: lambda parent, child: anchors.get(child),
                           clock=lambda: now[0], log=lambda level, text: logged.append((level, text)))
    listener.logged = logged
    web = GroundStationServer(live, {"mode": "live", "arena": None}, None, "127.0.0.1", 0, maps=listener.maps)
    web.start()
    yield listener, web, now
    web.stop()


def get_maps(web, query=""):
    c = http.client.HTTPConnection("127.0.0.1", web.port, timeout=10)
    c.request("GET", "/api/maps" + query, headers={"Host": "127.0.0.1:%d" % web.port})
    r = c.getresponse()
    body = json.loads(r.read())
    c.close()
    return r.status, body


def test_node_serves_a_published_grid_in_the_arena_frame(node_pieces):
    listener, web, now = node_pieces
    assert get_maps(web) == (200, {"version": 0, "maps": []})
    assert map_robot("/mbzirc2020_1/map") == "1" and map_robot("/mbzirc2020_1/map_metadata") is None
    assert listener.handle("1", grid_msg())
    status, body = get_maps(web)
    assert status == 200 and body["version"] == 1
    (m,) = body["maps"]
    assert (m["robot"], m["floor"], m["w"], m["h"], m["res"], m["cells"]) == ("1", 1, 4, 3, 0.5, "ffou" * 3)
    # anchor (20, 10, 90 deg) composed with the grid origin (-1, -0.5) in the map frame
    assert m["origin"] == pytest.approx([20.5, 9.0, math.pi / 2], abs=1e-3)
    assert get_maps(web, "?since=1") == (200, {"version": 1})
    # a malformed grid later: ignored, the good map stays
    now[0] = 20.0
    assert not listener.handle("1", grid_msg(data=[0] * 5))
    now[0] = 30.0
    assert not listener.handle("1", grid_msg(res=float("nan")))          # a second one within 10 s: not logged
    assert get_maps(web)[1]["version"] == 1
    assert len(listener.logged) == 1 and listener.logged[0][0] == "error" and "5 cells" in listener.logged[0][1]
    # replay pages get no maps
    assert get_maps(web, "?bag=x.bag")[1] == {"version": 0, "maps": []}


def test_grid_in_the_arena_frame_needs_no_tf_and_unanchored_maps_wait(node_pieces):
    listener, web, now = node_pieces
    assert not listener.handle("2", grid_msg(frame="mbzirc2020_2/map"))     # no transform yet
    assert listener.logged[0][0] == "warn" and "no transform arena -> mbzirc2020_2/map" in listener.logged[0][1]
    assert listener.handle("3", grid_msg(frame="/arena", origin=(3.0, 4.0)))
    (m,) = get_maps(web)[1]["maps"]
    assert m["robot"] == "3" and m["origin"] == [3.0, 4.0, 0.0] and m["floor"] is None   # robot 3 not heard
