"""Replay of a recorded trial: a timeline over a message source, folded into the same GroundStationState.

The page at replay time t shows `state.frame(t)` after every message stamped <= t was applied, exactly what
the live node showed at sim time t (its state had received the same messages; the bag's stamps are the sim
time at which the recorder received them). Scrubbing back restores the nearest earlier checkpoint (a copy
of the state taken every `checkpoint_every` sim seconds as the timeline first passes) and re-applies the
messages after it.
"""
from __future__ import annotations

import bisect
import copy
import threading
from typing import Any, Callable, Iterator, Optional, Protocol

from .state import GroundStationState

__all__ = ["MessageSource", "ListSource", "Replay"]

Message = tuple[str, Any, float]   # (topic, msg, t)


class MessageSource(Protocol):
    """A recorded trial: its time span and its messages in time order."""
    start: float
    end: float

    def messages(self, after: float) -> Iterator[Message]:
        """Messages with t > after, in time order."""


class ListSource:
    """A MessageSource over an in-memory list (tests, small recordings)."""

    def __init__(self, messages: list[Message]) -> None:
        self._msgs = sorted(messages, key=lambda m: m[2])
        self._times = [m[2] for m in self._msgs]
        self.start = self._times[0] if self._times else 0.0
        self.end = self._times[-1] if self._times else 0.0

    def messages(self, after: float) -> Iterator[Message]:
        return iter(self._msgs[bisect.bisect_right(self._times, after):])


SPEEDS = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0)


class Replay:
    """Play, pause, seek and speed over a MessageSource (thread-safe; the web server calls it)."""

    def __init__(self, source: MessageSource, make_state: Callable[[], GroundStationState],
                 checkpoint_every: float = 10.0) -> None:
        self.source = source
        self.make_state = make_state
        self.checkpoint_every = checkpoint_every
        self.lock = threading.Lock()
        self.playing = False
        self.speed = 1.0
        self._checkpoints: dict[int, tuple[float, GroundStationState]] = {}
        self._restart(source.start - 1e-6)

    # ------------------------------------------------------------------ timeline
    def _restart(self, t: float, state: Optional[GroundStationState] = None) -> None:
        self.state = state if state is not None else self.make_state()
        self.t = t
        self._it = self.source.messages(t)
        self._peek: Optional[Message] = None

    def _next(self) -> Optional[Message]:
        if self._peek is None:
            self._peek = next(self._it, None)
        return self._peek

    def _advance_to(self, target: float) -> None:
        """Apply every message with t <= target; checkpoints on the way."""
        while True:
            m = self._next()
            if m is None or m[2] > target:
                break
            self._checkpoint(m[2], inclusive=False)
            self.state.apply(m[0], m[1], m[2])
            self.t = max(self.t, m[2])
            self._peek = None
        self._checkpoint(target, inclusive=True)
        self.t = max(self.t, target)

    def _checkpoint(self, t_next: float, inclusive: bool) -> None:
        """Copy the state at the last multiple cp of checkpoint_every before t_next (at or before when
        inclusive) if the state holds exactly the messages <= cp: none applied after cp, none left before it."""
        span = t_next - self.source.start
        k = int(span // self.checkpoint_every)
        if not inclusive and k >= 1 and span == k * self.checkpoint_every:
            k -= 1
        cp = self.source.start + k * self.checkpoint_every
        if k >= 1 and k not in self._checkpoints and self.t <= cp:
            self._checkpoints[k] = (cp, copy.deepcopy(self.state))

    def seek(self, target: float) -> None:
        with self.lock:
            target = min(max(target, self.source.start), self.source.end)
            if target < self.t:
                k = max([k for k, (t, _) in self._checkpoints.items() if t <= target] or [0])
                if k:
                    t, st = self._checkpoints[k]
                    self._restart(t, copy.deepcopy(st))
                else:
                    self._restart(self.source.start - 1e-6)
            self._advance_to(target)

    def step(self, wall_dt: float) -> None:
        """Move the timeline by wall_dt x speed while playing (called by the server's frame clock)."""
        with self.lock:
            if not self.playing:
                return
            target = min(self.t + wall_dt * self.speed, self.source.end)
            self._advance_to(target)
            if target >= self.source.end:
                self.playing = False

    def control(self, req: dict) -> tuple[bool, str]:
        """Page / API request: {"action": "play"|"pause"|"seek"|"speed", "t": s, "speed": x}."""
        action = req.get("action")
        if action == "play":
            with self.lock:
                if self.t >= self.source.end:
                    self._restart(self.source.start - 1e-6)
                self.playing = True
        elif action == "pause":
            with self.lock:
                self.playing = False
        elif action == "seek":
            t = req.get("t")
            if not isinstance(t, (int, float)) or isinstance(t, bool) or t != t:
                return False, "seek needs a number t"
            self.seek(float(t))
        elif action == "speed":
            s = req.get("speed")
            if s not in SPEEDS:
                return False, "speed must be one of %s" % (SPEEDS,)
            with self.lock:
                self.speed = float(s)
        else:
            return False, "unknown action %r" % (action,)
        return True, ""

    def close(self) -> None:
        """Frees the source (a bag file); the replay is not used after this."""
        close = getattr(self.source, "close", None)
        if close is not None:
            close()

    def frame(self, tracks: bool = False) -> dict:
        with self.lock:
            out = self.state.frame(self.t, tracks=tracks)
            out["replay"] = {"t": self.t, "start": self.source.start, "end": self.source.end,
                             "playing": self.playing, "speed": self.speed}
            return out
