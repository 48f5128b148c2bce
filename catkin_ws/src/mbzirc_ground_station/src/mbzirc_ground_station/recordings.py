"""The recorded trials the page offers for replay: the bags under one results directory (pure, no ROS).

A page names a recording by its path relative to the results directory (as listed by `Recordings.list`).
The name comes from the network, so it is checked before any file is opened: no absolute path, no `..`,
nothing outside the directory once symbolic links are followed, only `*.bag` files that start with a rosbag
header. Anything else is refused with the reason (the page shows it).
"""
from __future__ import annotations

import os
from typing import NamedTuple

__all__ = ["Recordings", "RecordingError", "Recording", "default_results_dir", "BAG_MAGIC"]

BAG_MAGIC = b"#ROSBAG V2.0\n"     # the first line of every rosbag (format 2.0)
MAX_DEPTH = 3                      # results/<mission>/mission.bag sits at depth 2
MAX_LISTED = 500                   # newest first


def default_results_dir() -> str:
    """Where `make mission RECORD=1` writes: the `results/` folder of the repository holding this package
    (catkin_ws/src/mbzirc_ground_station -> ../../../results)."""
    package = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    return os.path.normpath(os.path.join(package, "..", "..", "..", "results"))


class RecordingError(ValueError):
    """A name that does not designate a recording; `code` is the HTTP answer (400 refused, 404 missing)."""

    def __init__(self, reason: str, code: int = 400) -> None:
        super().__init__(reason)
        self.code = code


class Recording(NamedTuple):
    name: str      # relative to the results directory, '/'-separated
    size: int      # bytes
    mtime: float   # s since the epoch


class Recordings:
    """The bags under `root` (which may not exist yet: then there are none)."""

    def __init__(self, root: str) -> None:
        self.root = os.path.realpath(root)

    def list(self) -> list[Recording]:
        found = []
        for folder, dirs, files in os.walk(self.root):
            depth = os.path.relpath(folder, self.root).count(os.sep) + (folder != self.root)
            if depth >= MAX_DEPTH:
                dirs[:] = []
            dirs[:] = [d for d in dirs if not d.startswith(".")]
            for f in files:
                if f.endswith(".bag"):
                    path = os.path.join(folder, f)
                    try:
                        st = os.stat(path)
                    except OSError:
                        continue
                    found.append(Recording(os.path.relpath(path, self.root).replace(os.sep, "/"), st.st_size,
                                           st.st_mtime))
        found.sort(key=lambda r: (-r.mtime, r.name))
        return found[:MAX_LISTED]

    def resolve(self, name: object) -> str:
        """The absolute path of the recording `name`, or RecordingError with the reason."""
        if not isinstance(name, str) or not name.strip():
            raise RecordingError("name a recording (a .bag under the results directory)")
        if "\0" in name or len(name) > 1000:
            raise RecordingError("not a recording name: %r" % name[:100])
        if name.startswith(("/", "\\")) or os.path.isabs(name):
            raise RecordingError("absolute paths are refused: name a bag relative to the results directory")
        if ".." in name.replace("\\", "/").split("/"):
            raise RecordingError("'..' is refused: only bags under the results directory can be replayed")
        if not name.endswith(".bag"):
            raise RecordingError("%r is not a bag (only .bag files can be replayed)" % name)
        path = os.path.realpath(os.path.join(self.root, name))
        if not path.startswith(self.root + os.sep):
            raise RecordingError("%r leads outside the results directory (a link?): refused" % name)
        if not os.path.isfile(path):
            raise RecordingError("no recording %r in the results directory" % name, 404)
        try:
            with open(path, "rb") as f:
                head = f.read(len(BAG_MAGIC))
        except OSError as ex:
            raise RecordingError("cannot read %r: %s" % (name, ex.strerror), 404) from None
        if head != BAG_MAGIC:
            raise RecordingError("%r is not a rosbag (no '#ROSBAG V2.0' header)" % name)
        return path
