"""report.png: the arena map (building, robot tracks, fires and when they went out) and the score over time.

Matplotlib with the Agg backend, so it runs headless in CI and on robots without a display.
"""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from mbzirc_arena.c3 import ARENA  # noqa: E402

from .summary import MissionRecord  # noqa: E402

KIND_STYLE = {"ground": ("s", "tab:brown"), "facade": ("^", "tab:red"), "indoor": ("o", "tab:purple")}


def write_report(rec: MissionRecord, path: str, title: str = "") -> None:
    """Draw the map and the score curve of a trial into `path` (PNG)."""
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(14, 6.5), gridspec_kw={"width_ratios": [1.3, 1]})
    for name, b in ((b.name, b.box) for b in ARENA.buildings):
        ax.add_patch(Rectangle((b[0], b[1]), b[3] - b[0], b[4] - b[1], facecolor="0.85", edgecolor="0.3"))
        ax.text((b[0] + b[3]) / 2, (b[1] + b[4]) / 2, name, ha="center", va="center", fontsize=8, color="0.3")
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
    fig.suptitle(title or f"MBZIRC C3 simulated trial, seed {rec.seed}")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
