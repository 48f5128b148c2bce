"""Indoor flights of the robots that run SLAM and their SLAM pose error against the truth (pure; the
referee's side).

An indoor flight is a contiguous period in which a robot's `localization/source` is `slam` (indoor_localization:
no GNSS fix, the anchored SLAM pose is the valid one) or the robot is truly indoors (its true pose inside a
building's footprint below the building's top), two such periods less than `JOIN_S` apart being one: with
GNSS denied indoors the two agree within a scan or two; without (the default worlds) only the truth says
when a robot was inside, and its SLAM pose is scored all the same. Its error is the horizontal distance
between the robot's `localization/pose` (published on every SLAM pose once anchored, whatever the source)
and the simulator's true pose, at every true pose of the period (/sim/robots, 2 Hz), the SLAM pose
interpolated at that time between two poses at most `max_gap` s apart (none: the sample is skipped). Its
floor is the storey of most of its true heights (rule: `mbzirc_arena.floor_of`); `on_slam_s` says how long
the source was `slam` during it. `rms_on_slam_m` / `max_on_slam_m` score only the samples while the source was
`slam`: the pose the robot flew on (with GNSS denied indoors a robot whose source went `none` holds, and the
SLAM pose it no longer uses may be anywhere: an unanchored map frame read kilometres off, explore + GNSS-denied
mission, seeds 101-102); None when the source was never `slam` (GNSS indoors: the SLAM pose is only watched).
"""
from __future__ import annotations

import bisect
import math
from collections import Counter
from dataclasses import dataclass, field
from typing import Callable, Optional, Sequence

__all__ = ["SlamRecord", "periods", "indoor_periods", "joined", "interpolate_xy", "flight_summary",
           "anchor_from_pair", "is_indoors", "MAX_GAP_S"]

SLAM = "slam"
MAX_GAP_S = 0.25      # s: two SLAM poses further apart do not interpolate (15 Hz scans, a few dropped)
JOIN_S = 1.5          # s: two indoor periods closer than this are one flight (2 Hz truth, source latency)
Sample = tuple        # (t, x, y, z)


def periods(changes: Sequence[tuple], t_end: float, source: str = SLAM) -> list[tuple]:
    """[(t_start, t_end)] of the contiguous periods where the source was `source`, from its changes
    [(t, source)] in time order; one still open ends at t_end."""
    out, start = [], None
    for t, s in changes:
        if s == source and start is None:
            start = t
        elif s != source and start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, max(start, t_end)))
    return out


def is_indoors(x: float, y: float, z: float, footprints: Sequence[Sequence[float]]) -> bool:
    """Inside a footprint (x_min, y_min, x_max, y_max, top) and below its top."""
    return any(b[0] <= x <= b[2] and b[1] <= y <= b[3] and z < b[4] for b in footprints)


def indoor_periods(truth: Sequence[Sample], footprints: Sequence[Sequence[float]]) -> list[tuple]:
    """[(t_first, t_last)] of the runs of consecutive true poses indoors."""
    out, start, last = [], None, None
    for t, x, y, z in truth:
        if is_indoors(x, y, z, footprints):
            start = t if start is None else start
            last = t
        elif start is not None:
            out.append((start, last))
            start = None
    if start is not None:
        out.append((start, last))
    return out


def joined(spans: Sequence[tuple], join: float = JOIN_S) -> list[tuple]:
    """The union of periods, those less than `join` apart merged."""
    out: list[list] = []
    for t0, t1 in sorted(spans):
        if out and t0 - out[-1][1] < join:
            out[-1][1] = max(out[-1][1], t1)
        else:
            out.append([t0, t1])
    return [tuple(p) for p in out]


def _overlap(span: tuple, spans: Sequence[tuple]) -> float:
    return sum(max(0.0, min(span[1], b) - max(span[0], a)) for a, b in spans)


def interpolate_xy(samples: Sequence[Sample], t: float, max_gap: float = MAX_GAP_S,
                   times: Optional[Sequence[float]] = None) -> Optional[tuple]:
    """(x, y) of time-ordered samples at t, linear between the two around it; None when t is outside them
    or they are more than max_gap apart. `times`: the samples' times, when the caller has them already."""
    times = [s[0] for s in samples] if times is None else times
    i = bisect.bisect_left(times, t)
    if i < len(samples) and times[i] == t:
        return samples[i][1], samples[i][2]
    if i == 0 or i == len(samples):
        return None
    a, b = samples[i - 1], samples[i]
    if b[0] - a[0] > max_gap:
        return None
    f = (t - a[0]) / (b[0] - a[0])
    return a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])


def anchor_from_pair(arena_pose: tuple, map_pose: tuple) -> tuple:
    """The pose (x, y, yaw) of the map frame in the arena given one robot pose (x, y, yaw) in both."""
    yaw = arena_pose[2] - map_pose[2]
    c, s = math.cos(yaw), math.sin(yaw)
    return (arena_pose[0] - (c * map_pose[0] - s * map_pose[1]),
            arena_pose[1] - (s * map_pose[0] + c * map_pose[1]), math.atan2(math.sin(yaw), math.cos(yaw)))


def _rms(errors: Sequence[float]) -> Optional[float]:
    return round(math.sqrt(sum(e * e for e in errors) / len(errors)), 3) if errors else None


def flight_summary(robot: str, period: tuple, slam: Sequence[Sample], truth: Sequence[Sample],
                   floor_of: Callable[[float], int], max_gap: float = MAX_GAP_S, on_slam_s: float = 0.0,
                   slam_spans: Sequence[tuple] = ()) -> dict:
    """One flight's entry of summary.json: robot, floor, start, end, duration, time on the slam source,
    SLAM poses, error samples, RMS and max, and RMS and max while on the slam source (`slam_spans`), with
    the error of its first sample there and the time of its worst."""
    t0, t1 = period
    inside = [s for s in slam if t0 <= s[0] <= t1]
    times = [s[0] for s in inside]
    errors, used, used_t, floors = [], [], [], Counter()
    for t, x, y, z in (s for s in truth if t0 <= s[0] <= t1):
        floors[floor_of(z)] += 1
        est = interpolate_xy(inside, t, max_gap, times)
        if est is not None:
            errors.append(math.hypot(est[0] - x, est[1] - y))
            if any(a <= t <= b for a, b in slam_spans):
                used.append(errors[-1])
                used_t.append(t)
    if not floors:                       # no truth in the flight: the SLAM pose's own heights say where
        floors.update(floor_of(s[3]) for s in inside)
    return {"robot": robot, "floor": floors.most_common(1)[0][0] if floors else None,
            "t_start": round(t0, 2), "t_end": round(t1, 2), "duration_s": round(t1 - t0, 2),
            "on_slam_s": round(on_slam_s, 2), "slam_poses": len(inside), "samples": len(errors),
            "rms_error_m": _rms(errors), "max_error_m": round(max(errors), 3) if errors else None,
            "rms_on_slam_m": _rms(used), "max_on_slam_m": round(max(used), 3) if used else None,
            # where the error came from: the anchor's inheritance (the first sample) or later (the worst's time)
            "first_on_slam_m": round(used[0], 3) if used else None,
            "t_max_on_slam": round(used_t[max(range(len(used)), key=used.__getitem__)], 2) if used else None}


@dataclass
class SlamRecord:
    """What the referee keeps of the robots that run SLAM (those with a localization source): sources, SLAM
    poses, truth, anchors; `footprints` (x_min, y_min, x_max, y_max, top) say what is indoors."""
    footprints: tuple = ()
    sources: dict[str, list[tuple]] = field(default_factory=dict)     # robot -> [(t, source)] changes
    poses: dict[str, list[Sample]] = field(default_factory=dict)      # robot -> localization/pose
    truth: dict[str, list[Sample]] = field(default_factory=dict)      # robot -> true poses
    anchors: dict[str, tuple] = field(default_factory=dict)           # robot -> newest arena <- <ns>/map
    been_inside: set = field(default_factory=set)                     # robots once indoors or on slam

    def set_source(self, robot: str, t: float, source: str) -> bool:
        """Record the robot's source; True when it changed."""
        changes = self.sources.setdefault(robot, [])
        if changes and changes[-1][1] == source:
            return False
        changes.append((t, source))
        if source == SLAM:
            self.been_inside.add(robot)
        return True

    def on_slam(self, robot: str) -> bool:
        changes = self.sources.get(robot)
        return bool(changes) and changes[-1][1] == SLAM

    def add_pose(self, robot: str, t: float, x: float, y: float, z: float) -> None:
        """A localization/pose of a robot that runs SLAM (in time order: a late one is dropped). All are
        kept (15 Hz, 4 floats: about 5 MB for three robots over a whole trial): a flight is known to have
        begun only at the next true pose."""
        if robot in self.sources:
            poses = self.poses.setdefault(robot, [])
            if not poses or t > poses[-1][0]:
                poses.append((t, x, y, z))

    def add_truth(self, robot: str, t: float, x: float, y: float, z: float) -> None:
        """A true pose, kept for the robots that run SLAM (the others have no indoor flight to score)."""
        if robot in self.sources:
            tr = self.truth.setdefault(robot, [])
            if not tr or t > tr[-1][0]:
                tr.append((t, x, y, z))
                if is_indoors(x, y, z, self.footprints):
                    self.been_inside.add(robot)

    def flights(self, t_end: float, floor_of: Callable[[float], int]) -> list[dict]:
        """Every indoor flight of every robot, in time order."""
        out = []
        for robot, changes in sorted(self.sources.items()):
            on_slam = periods(changes, t_end)
            truth = self.truth.get(robot, [])
            for p in joined(on_slam + indoor_periods(truth, self.footprints)):
                out.append(flight_summary(robot, p, self.poses.get(robot, []), truth, floor_of,
                                          on_slam_s=_overlap(p, on_slam), slam_spans=on_slam))
        return sorted(out, key=lambda f: (f["t_start"], f["robot"]))

    def tracks(self) -> dict:
        """robot -> its source changes, localization poses and true poses (3 decimals) for the robots once
        indoors: what the flights' errors were computed from, for looking at where and when the pose
        went off (slam_tracks.json beside summary.json)."""
        def rounded(samples):
            return [[round(v, 3) for v in s] for s in samples]
        return {robot: {"sources": [[round(t, 3), s] for t, s in self.sources.get(robot, [])],
                        "poses": rounded(self.poses.get(robot, [])), "truth": rounded(self.truth.get(robot, []))}
                for robot in sorted(self.been_inside)}

    def map_floors(self, t_end: float, floor_of: Callable[[float], int]) -> dict[str, int]:
        """robot -> the floor its map belongs to: the floor of most of its time in indoor flights (robots
        never indoors have no indoor map)."""
        time_on = {}
        for f in self.flights(t_end, floor_of):
            if f["floor"] is not None:
                per = time_on.setdefault(f["robot"], Counter())
                per[f["floor"]] += f["duration_s"] + 1e-6
        return {robot: per.most_common(1)[0][0] for robot, per in time_on.items()}
