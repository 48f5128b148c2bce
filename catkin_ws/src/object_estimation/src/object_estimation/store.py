"""The object estimator's tracks on disk: the generic guarded state file (mbzirc_ros_utils.state_file)
with the estimator's format and a check that a track list is there.

Why: the estimator is the only holder of what every robot has seen. When it crashes (kill -9, a tf2
abort) roslaunch respawns it, and without this it would start with no tracks: fires already found would
be searched again, fires already put out would come back as ACTIVE, and new ids would name old objects.
With a state file it resumes with the same tracks, statuses and ids. The guards (another mission's file,
a file saved "later than now", a foreign or corrupt file) are state_file's.
"""
from __future__ import annotations

from typing import Any, Dict

from mbzirc_ros_utils import state_file
from mbzirc_ros_utils.state_file import INVALID, MISSING, OK, STALE, Loaded, save  # noqa: F401 (this module's API)

FORMAT = 'mbzirc_agents/estimator_tracks'
VERSION = 1


def encode(state: Dict[str, Any], mission: str, saved_at: float) -> str:
    """The file contents for an estimator state (`ObjectEstimator.to_state`)."""
    return state_file.encode(state, FORMAT, VERSION, mission, saved_at)


def load(path: str, mission: str, now: float) -> Loaded:
    """Read and check a tracks file (see state_file.load); INVALID as well when it holds no track list."""
    res = state_file.load(path, FORMAT, VERSION, mission, now, what='estimator tracks')
    if res.kind != OK:
        return res
    if not isinstance(res.state.get('tracks'), list):
        return Loaded(INVALID, reason=f'{path} has no track list')
    return Loaded(OK, state={'next_id': res.state.get('next_id'), 'tracks': res.state['tracks'],
                             'saved_at': res.state['saved_at']},
                  reason=f"{len(res.state['tracks'])} tracks saved at t={res.state['saved_at']:.1f} s")
