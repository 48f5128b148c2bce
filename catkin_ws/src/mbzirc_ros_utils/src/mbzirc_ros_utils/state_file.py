"""A node's state on disk (pure, no ROS): atomic save, guarded load. Used by every node that must resume
after a respawn (the object estimator's tracks, the region manager's reservations).

Why: roslaunch respawns a node killed by kill -9 or an abort, but a node holding the mission's shared state
in memory would start empty. With a state file it resumes where it was.

Guards against resuming from the wrong file:
- the file says which kind of state it holds (`format`, `version`), which mission wrote it (`mission`: the
  master's `/run_id`, new for every roscore) and when (`saved_at`, ROS time): a file of another mission, or
  saved "later than now" (a new simulation restarts its clock at 0), is stale and ignored;
- a file that is not of the expected format, unreadable or malformed is rejected as a whole.
The writer replaces the file atomically (temporary file in the same directory + fsync + os.replace), so a
crash mid-write leaves the previous complete file.
"""
from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass
from typing import Any, Dict, Optional

# a file saved up to this many seconds "in the future" is still ours (clock granularity between processes)
FUTURE_TOLERANCE_S = 1.0

OK, MISSING, STALE, INVALID = 'ok', 'missing', 'stale', 'invalid'
HEADER_KEYS = ('format', 'version', 'mission', 'saved_at')


@dataclass
class Loaded:
    """Outcome of `load`: `kind` OK (then `state` is the saved state, without the header fields but with
    `saved_at`), MISSING, STALE or INVALID; `reason` says why in words (for the log)."""
    kind: str
    state: Optional[Dict[str, Any]] = None
    reason: str = ''


def encode(state: Dict[str, Any], fmt: str, version: int, mission: str, saved_at: float) -> str:
    """The file contents for `state` (a JSON-able dict whose keys are not header keys)."""
    doc = {'format': fmt, 'version': version, 'mission': mission, 'saved_at': float(saved_at)}
    doc.update({k: v for k, v in state.items() if k not in HEADER_KEYS})
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


def load(path: str, fmt: str, version: int, mission: str, now: float, what: str = 'state') -> Loaded:
    """Read and check a file written by `encode` + `save`.

    Args:
        fmt, version: what the file must say it holds.
        mission: this mission's identity; a file of another mission is STALE ('' on either side: not
            checked).
        now: current ROS time; a file saved after it (beyond FUTURE_TOLERANCE_S) is STALE (0: not checked,
            e.g. no /clock yet).
        what: the state's name in the reasons ('tracks', 'regions').
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
    if not isinstance(doc, dict) or doc.get('format') != fmt:
        return Loaded(INVALID, reason=f'{path} is not a {what} file (no format {fmt!r})')
    if doc.get('version') != version:
        return Loaded(INVALID, reason=f"{path} has version {doc.get('version')!r}, this node reads {version}")
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
    state = {k: v for k, v in doc.items() if k not in HEADER_KEYS}
    state['saved_at'] = saved_at
    return Loaded(OK, state=state, reason=f'{what} saved at t={saved_at:.1f} s')
