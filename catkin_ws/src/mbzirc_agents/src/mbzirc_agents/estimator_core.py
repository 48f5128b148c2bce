"""Object estimator (pure): fuses the detections of every robot into tracks of fires and holes.

Why: three robots looking at one fire must give the central unit one fire, with one id, so that it
assigns it once. Objects of C3 do not move, so a track is a static 3D point with a covariance, fused
with each associated detection by an information-filter update.

Track life:
- a detection farther than `gate` (m) from every track of its type starts a new track, status DETECTED
  (tentative);
- after `min_updates` updates the track is confirmed: ACTIVE;
- a track not updated for `lost_time` s becomes LOST (a tentative one is dropped instead: most likely a
  false positive); an update brings a LOST track back to ACTIVE;
- `set_status` (the `set_object_status` service) may set any status; INACTIVE and EXTINGUISHED are
  final: detections still refine the track (so no duplicate is created) but do not change its status.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence

import numpy as np

from . import constants as C
from .geometry import in_footprint, nearest_face

STICKY = (C.STATUS_INACTIVE, C.STATUS_EXTINGUISHED)


@dataclass
class Detection:
    """One sensed object in the global frame."""
    type: int
    position: np.ndarray                 # (3,)
    covariance: np.ndarray               # (3, 3)
    stamp: float                         # s
    agent_id: str = ''
    camera_direction: int = 0
    scale: tuple = (0.0, 0.0, 0.0)


@dataclass
class Track:
    """A fused object."""
    id: int
    type: int
    position: np.ndarray
    covariance: np.ndarray
    first_seen: float
    last_update: float
    num_updates: int = 1
    status: int = C.STATUS_DETECTED
    sub_type: int = C.SUBTYPE_UNKNOWN
    scale: tuple = (0.0, 0.0, 0.0)
    agents: set = field(default_factory=set)


def classify_fire(position: Sequence[float], buildings: Sequence[Sequence[float]]) -> int:
    """SUBTYPE_* of a fire at position: inside a footprint -> INDOOR, low and away from walls -> GROUND."""
    if in_footprint(position, buildings, margin=-0.5):
        return C.SUBTYPE_INDOOR
    _, d = nearest_face(position, buildings)
    if position[2] < 1.5 and d > 1.0:
        return C.SUBTYPE_GROUND
    return C.SUBTYPE_FACADE


def sane_covariance(cov: np.ndarray, default: np.ndarray) -> np.ndarray:
    """cov when it is a finite, symmetric positive-definite 3x3 matrix, else default."""
    try:
        cov = np.asarray(cov, dtype=float).reshape(3, 3)
        if not np.all(np.isfinite(cov)):
            return default
        cov = 0.5 * (cov + cov.T)
        np.linalg.cholesky(cov)
        return cov
    except (ValueError, np.linalg.LinAlgError):
        return default


class ObjectEstimator:
    """Associates detections into tracks (see the module docstring).

    Args:
        gates: association distance (m) per object type; other types use `default_gate`.
        min_updates: updates before a track is confirmed (ACTIVE).
        lost_time: s without an update before a track is LOST (or dropped while tentative).
        default_covariance: used when a detection carries no valid covariance.
        process_noise: variance (m^2) added per update so that a track never becomes overconfident.
    """

    def __init__(self, gates: Optional[Dict[int, float]] = None, default_gate: float = 2.0,
                 min_updates: int = 5, lost_time: float = 10.0,
                 default_covariance: Sequence[float] = (1.5, 1.5, 0.5), process_noise: float = 1e-3,
                 buildings: Sequence[Sequence[float]] = tuple(C.BUILDINGS)) -> None:
        self.gates = dict(gates or {C.TYPE_FIRE: 2.0, C.TYPE_HOLE: 0.4})
        self.default_gate = default_gate
        self.min_updates = int(min_updates)
        self.lost_time = float(lost_time)
        self.default_cov = np.diag(np.square(np.asarray(default_covariance, dtype=float)))
        self.process_noise = float(process_noise)
        self.buildings = [tuple(b) for b in buildings]
        self.tracks: Dict[int, Track] = {}
        self._next_id = 1

    # ---- updates ----------------------------------------------------------------------------------
    def add(self, det: Detection) -> Track:
        """Fuse one detection; returns the track it went to (new or existing)."""
        z = np.asarray(det.position, dtype=float).reshape(3)
        if not np.all(np.isfinite(z)):
            raise ValueError('detection position is not finite')
        r = sane_covariance(det.covariance, self.default_cov)
        track = self._associate(det.type, z)
        if track is None:
            track = Track(id=self._next_id, type=det.type, position=z.copy(), covariance=r.copy(),
                          first_seen=det.stamp, last_update=det.stamp, scale=tuple(det.scale))
            self._next_id = self._next_id % 65535 + 1
            self.tracks[track.id] = track
        else:
            p = track.covariance + np.eye(3) * self.process_noise
            k = p @ np.linalg.inv(p + r)
            track.position = track.position + k @ (z - track.position)
            track.covariance = (np.eye(3) - k) @ p
            track.num_updates += 1
            track.last_update = max(track.last_update, det.stamp)
        track.agents.add(det.agent_id)
        if track.type == C.TYPE_FIRE:
            track.sub_type = classify_fire(track.position, self.buildings)
        if track.status not in STICKY:
            if track.num_updates >= self.min_updates:
                track.status = C.STATUS_ACTIVE
            elif track.status == C.STATUS_LOST:
                track.status = C.STATUS_ACTIVE
        return track

    def _associate(self, obj_type: int, z: np.ndarray) -> Optional[Track]:
        """The nearest track of the same type within the gate, if any."""
        gate = self.gates.get(obj_type, self.default_gate)
        best, best_d = None, gate
        for t in self.tracks.values():
            if t.type != obj_type:
                continue
            d = float(np.linalg.norm(t.position - z))
            if d <= best_d:
                best, best_d = t, d
        return best

    def tick(self, now: float) -> None:
        """Age the tracks: LOST after lost_time without updates; tentative ones are dropped instead."""
        for tid in list(self.tracks):
            t = self.tracks[tid]
            if now - t.last_update <= self.lost_time:
                continue
            if t.status == C.STATUS_DETECTED and t.num_updates < self.min_updates:
                del self.tracks[tid]
            elif t.status == C.STATUS_ACTIVE:
                t.status = C.STATUS_LOST

    def set_status(self, object_id: int, status: int, object_type: int = 0) -> str:
        """Set a track's status; returns '' or the reason it could not (unknown id, type mismatch)."""
        t = self.tracks.get(int(object_id))
        if t is None:
            return f'unknown object id {object_id}'
        if status not in C.STATUS_NAMES:
            return f'unknown status {status}'
        if object_type and object_type != t.type:
            return f'object {object_id} has type {t.type}, not {object_type}'
        t.status = int(status)
        return ''

    def objects(self, include_tentative: bool = False) -> List[Track]:
        """Tracks to publish, by id."""
        return [t for _, t in sorted(self.tracks.items())
                if include_tentative or t.num_updates >= self.min_updates or t.status in STICKY]
