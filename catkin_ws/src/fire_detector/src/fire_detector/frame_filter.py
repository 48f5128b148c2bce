"""The frame filter: a fire is only believed after many consecutive hot frames."""
from __future__ import annotations


class FrameFilter:
    """Counts consecutive hot frames and confirms a fire after more than `num_frame_filter` of them.

    Args:
        num_frame_filter: a fire is confirmed when more than this many consecutive frames are hot
            (the original's false-positive filter: flickering hot pixels and passing warm objects).
        false_negative_tolerance: once confirmed, up to this many consecutive cold frames are forgiven
            (the fire stays confirmed but those frames give no detection); one more resets the count.

    .. note:: while a cold frame is being forgiven the hot count is kept, not increased, so a fire that
       blinks hot/cold is never confirmed from scratch: the tolerance only protects confirmed fires.
    """

    def __init__(self, num_frame_filter: int, false_negative_tolerance: int = 0) -> None:
        self.num_frame_filter = max(0, int(num_frame_filter))
        self.false_negative_tolerance = max(0, int(false_negative_tolerance))
        self.hot_count = 0
        self.cold_count = 0

    @property
    def confirmed(self) -> bool:
        """True while the filter believes in a fire (including forgiven cold frames)."""
        return self.hot_count > self.num_frame_filter

    def update(self, hot: bool) -> bool:
        """Feeds one frame; returns True when this frame is a confirmed hot detection."""
        if hot:
            self.hot_count += 1
            self.cold_count = 0
            return self.confirmed
        if self.confirmed and self.cold_count < self.false_negative_tolerance:
            self.cold_count += 1
            return False
        self.reset()
        return False

    def reset(self) -> None:
        """Forgets every frame seen."""
        self.hot_count = 0
        self.cold_count = 0
