"""The object estimator's tracks on disk (pure, no ROS): atomic save, guarded load.

Why: the estimator is the only holder of what every robot has seen. When it crashes (kill -9, a tf2
abort) roslaunch respawns it, and without this it would start with no tracks: fires already found would
be searched again, fires already put out would come back as ACTIVE, and new ids would name old objects.
With a state file it resumes with the same tracks, statuses and ids.

Guards against resuming from the wrong file:
- the file says which mission wrote it (`mission`: the master's `/run_id`, new for every roscore) and
  when (`saved_at`, ROS time): a file of another mission, or saved "later than now" (a new simulation
  restarts its clock at 0), is stale and ignored;
- a file that is not ours (no `format` marker), unreadable or malformed is rejected as a whole.
The writer replaces the file atomically (temporary file in the same directory + fsync + os.replace), so a
crash mid-write leaves the previous complete file.
"""
from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass
from typing import Any, Dict, Optional

FORMAT = 'mbzirc_agents/estimator_tracks'
VERSION = 1
# a file saved up to this many seconds "in the future" is still ours (clock granularity between processes)
FUTURE_TOLERANCE_S = 1.0

OK, MISSING, STALE, INVALID = 'ok', 'missing', 'stale', 'invalid'


@dataclass
class Loaded:
    """Outcome of `load`: `kind` OK (then `state` is the estimator state), MISSING, STALE or INVALID;
    `reason` says why in words (for the log)."""
    kind: str
    state: Optional[Dict[str, Any]] = None
    reason: str = ''


def encode(state: Dict[str, Any], mission: str, saved_at: float) -> str:
    """The file contents for an estimator state (`ObjectEstimator.to_state`)."""
    doc = {'format': FORMAT, 'version': VERSION, 'mission': mission, 'saved_at': float(saved_at)}
    doc.update(state)
    return json.dumps(doc, separators=(',', ':'))


def save(path: str, text: str) -> None:
    """Write text to path atomically (OSError on failure; the previous file is then untouched)."""
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix='.' + os.path.basename(path) + '.', suffix='.tmp', dir=directory)
    try:
        with os.fdopen(fd, 'w', encoding='utf-8') as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def load(path: str, mission: str, now: float) -> Loaded:
    """Read and check a state file written by `encode` + `save`.

    Args:
        mission: this mission's identity; a file of another mission is STALE ('' on either side: not
            checked).
        now: current ROS time; a file saved after it (beyond FUTURE_TOLERANCE_S) is STALE (0: not checked,
            e.g. no /clock yet).
    """
    try:
        with open(path, encoding='utf-8') as f:
            text = f.read()
    except FileNotFoundError:
        return Loaded(MISSING, reason=f'no state file {path}')
    except (OSError, UnicodeDecodeError) as e:
        return Loaded(INVALID, reason=f'cannot read {path}: {e}')
    try:
        doc = json.loads(text)
    except ValueError as e:
        return Loaded(INVALID, reason=f'{path} is not JSON ({e}): corrupt')
    if not isinstance(doc, dict) or doc.get('format') != FORMAT:
        return Loaded(INVALID, reason=f'{path} is not an estimator tracks file (no format {FORMAT!r})')
    if doc.get('version') != VERSION:
        return Loaded(INVALID, reason=f"{path} has version {doc.get('version')!r}, this estimator reads {VERSION}")
    try:
        saved_at = float(doc['saved_at'])
        file_mission = str(doc.get('mission') or '')
    except (KeyError, TypeError, ValueError) as e:
        return Loaded(INVALID, reason=f'{path}: bad saved_at / mission ({e})')
    if mission and file_mission and file_mission != mission:
        return Loaded(STALE, reason=f'{path} is from another mission (run_id {file_mission}, now {mission})')
    if now > 0 and saved_at > now + FUTURE_TOLERANCE_S:
        return Loaded(STALE, reason=f'{path} was saved at t={saved_at:.1f} s, later than now ({now:.1f} s): '
                                    'from an earlier simulation')
    if not isinstance(doc.get('tracks'), list):
        return Loaded(INVALID, reason=f'{path} has no track list')
    return Loaded(OK, state={'next_id': doc.get('next_id'), 'tracks': doc['tracks'], 'saved_at': saved_at},
                  reason=f"{len(doc['tracks'])} tracks saved at t={saved_at:.1f} s")
