"""report.png: the arena map (building, robot tracks, fires and when they went out), the score over time and,
when robots flew indoors on SLAM, one panel per floor with its SLAM map (map_floor<N>) and each indoor
flight's true track beside its SLAM track.

Matplotlib with the Agg backend, so it runs headless in CI and on robots without a display.
"""
from __future__ import annotations

from typing import Optional

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from mbzirc_arena.c3 import ARENA  # noqa: E402

from .slam_maps import ArenaMap  # noqa: E402
from .summary import MissionRecord  # noqa: E402

KIND_STYLE = {"ground": ("s", "tab:brown"), "facade": ("^", "tab:red"), "indoor": ("o", "tab:purple")}
MAP_COLOURS = ListedColormap(["#d9d9d9", "white", "black"])   # unknown, free, occupied (slam_maps codes)
MAP_DRAWN_SIDE = 800       # cells per side drawn at most (max-pooled beyond: walls survive, drawing stays fast)
MAP_MARGIN_M = 4.0         # m around the indoor flights' tracks in a floor panel


def write_report(rec: MissionRecord, path: str, title: str = "",
                 floor_maps: Optional[dict[int, ArenaMap]] = None) -> None:
    """Draw the map, the score curve and the SLAM floor maps (floor -> map) of a trial into `path` (PNG)."""
    floors = sorted((floor_maps or {}).items())
    fig = plt.figure(figsize=(14, 12 if floors else 6.5))
    outer = fig.add_gridspec(2 if floors else 1, 1, height_ratios=[6.5, 5.5] if floors else None)
    top = outer[0].subgridspec(1, 2, width_ratios=[1.3, 1])
    ax, ax2 = fig.add_subplot(top[0]), fig.add_subplot(top[1])
    _draw_arena(ax, rec)
    _draw_score(ax2, rec)
    if floors:
        flights = rec.indoor_flights()
        row = outer[1].subgridspec(1, max(len(floors), 2))
        for i, (floor, m) in enumerate(floors):
            _draw_floor_map(fig.add_subplot(row[i]), rec, floor, m, [f for f in flights if f["floor"] == floor])
    fig.suptitle(title or f"MBZIRC C3 simulated trial, seed {rec.seed}")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _draw_buildings(ax, filled: bool = True) -> None:
    """The buildings' outlines: filled and named on the arena map, bare lines over a SLAM map."""
    for name, b in ((b.name, b.box) for b in ARENA.buildings):
        ax.add_patch(Rectangle((b[0], b[1]), b[3] - b[0], b[4] - b[1], facecolor="0.85" if filled else "none",
                               edgecolor="0.3" if filled else "tab:blue", lw=1 if filled else 0.8))
        if filled:
            ax.text((b[0] + b[3]) / 2, (b[1] + b[4]) / 2, name, ha="center", va="center", fontsize=8, color="0.3")


def _draw_arena(ax, rec: MissionRecord) -> None:
    """The arena from above: buildings, robot tracks (crashes marked), fires and when they went out."""
    _draw_buildings(ax)
    for robot, tr in sorted(rec.tracks.items()):
        if len(tr) < 2:
            continue
        xs, ys = [p[1] for p in tr], [p[2] for p in tr]
        line, = ax.plot(xs, ys, lw=1.2, label=f"{robot} ({rec.robot_kinds.get(robot, '?')})")
        ax.plot(xs[0], ys[0], "o", color=line.get_color(), ms=5)
        if robot in rec.crashes or f"mbzirc2020_{robot}" in rec.crashes:
            ax.plot(xs[-1], ys[-1], "x", color="k", ms=12, mew=3)
    for f in rec.fires.values():
        marker, color = KIND_STYLE.get(f.kind, ("*", "k"))
        ax.plot(f.position[0], f.position[1], marker, color=color if f.extinguished else "orange",
                mec="k", ms=10)
        when = f"out {f.t_extinguished:.0f}s" if f.extinguished and f.t_extinguished is not None else \
            f"{100 * f.progress:.0f}%"
        ax.annotate(f"{f.kind} F{f.floor}: {when}", (f.position[0], f.position[1]), fontsize=7,
                    xytext=(4, 4 + 9 * f.floor), textcoords="offset points")  # floors share x, y
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("arena: tracks, fires (orange = still burning)")
    ax.legend(loc="lower right", fontsize=7)
    ax.grid(alpha=0.3)


def _draw_score(ax2, rec: MissionRecord) -> None:
    """The score over time, a dotted line when each fire went out."""
    if rec.score_history:
        ts = [t for t, _ in rec.score_history] + [rec.elapsed]
        ss = [s for _, s in rec.score_history] + [rec.score]
        ax2.step(ts, ss, where="post", color="tab:blue")
    for f in rec.fires.values():
        if f.extinguished and f.t_extinguished is not None:
            ax2.axvline(f.t_extinguished, color=KIND_STYLE.get(f.kind, ("", "k"))[1], ls=":", lw=1)
    ax2.set_xlim(0, max(rec.duration, rec.elapsed))
    ax2.set_ylim(0, max(1, len(rec.fires)) + 0.5)
    ax2.set_xlabel("sim time (s)")
    ax2.set_ylabel("score")
    ax2.set_title(f"score {rec.score:.2f} / {len(rec.fires)}; crashes: {', '.join(rec.crashes) or 'none'}")
    ax2.grid(alpha=0.3)


def _pooled(codes: np.ndarray, side: int = MAP_DRAWN_SIDE) -> np.ndarray:
    """codes max-pooled by whole blocks to at most `side` per side (occupied wins, as in a merge)."""
    k = max(1, -(-max(codes.shape) // side))
    if k == 1:
        return codes
    h, w = -(-codes.shape[0] // k), -(-codes.shape[1] // k)
    padded = np.zeros((h * k, w * k), dtype=codes.dtype)
    padded[:codes.shape[0], :codes.shape[1]] = codes
    return padded.reshape(h, k, w, k).max(axis=(1, 3))


def _draw_floor_map(ax, rec: MissionRecord, floor: int, m: ArenaMap, flights: list) -> None:
    """One floor's SLAM map, the building outlines, and each flight's true (solid) and SLAM (dashed) track."""
    ax.imshow(_pooled(m.codes), cmap=MAP_COLOURS, vmin=0, vmax=2, origin="lower", extent=m.extent,
              interpolation="nearest")
    _draw_buildings(ax, filled=False)
    xs, ys = [], []
    for f in flights:
        inside = lambda s: f["t_start"] <= s[0] <= f["t_end"]   # noqa: E731
        truth = [s for s in rec.slam.truth.get(f["robot"], []) if inside(s)]
        slam = [s for s in rec.slam.poses.get(f["robot"], []) if inside(s)]
        line, = ax.plot([s[1] for s in truth], [s[2] for s in truth], lw=1.2,
                        label=f"{f['robot']} true, t {f['t_start']:.0f}-{f['t_end']:.0f}s")
        ax.plot([s[1] for s in slam], [s[2] for s in slam], "--", lw=1, color=line.get_color())
        xs += [s[1] for s in truth + slam]
        ys += [s[2] for s in truth + slam]
    if xs:
        ax.set_xlim(min(xs) - MAP_MARGIN_M, max(xs) + MAP_MARGIN_M)
        ax.set_ylim(min(ys) - MAP_MARGIN_M, max(ys) + MAP_MARGIN_M)
    errs = ", ".join(f"{f['robot']}: {f['rms_error_m']}/{f['max_error_m']} m" for f in flights
                     if f["rms_error_m"] is not None)
    ax.set_title(f"floor {floor}: SLAM map; dashed = SLAM pose\nRMS/max error {errs or 'n/a'}", fontsize=9)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7)
    if flights:
        ax.legend(loc="lower right", fontsize=6)
