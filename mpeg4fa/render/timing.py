"""When each stream frame is shown: a constant-rate output schedule over the stream's timestamps.

Streams carry presentation times (fps, skipped frames, time codes), so their
frames need not be evenly spaced. Video files want a constant rate: output frame
``j`` at ``j / fps`` shows the latest stream frame whose time has come, so a
skipped stretch holds its frame and frame ``k`` appears at the first output
tick at or after its presentation time (exactly at it when the rates match).
Times are measured from the first frame, where the audio starts too.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mpeg4fa.fba.stream import FapStream
from mpeg4fa.render.errors import RenderError

_EPS = 1e-9


@dataclass(frozen=True)
class Schedule:
    fps: float
    source: np.ndarray   # (n_out,) stream frame index shown at each output frame
    times: np.ndarray    # (n_stream,) presentation time of each stream frame, s from the first

    @property
    def n_frames(self) -> int:
        return len(self.source)

    @property
    def duration(self) -> float:
        return self.n_frames / self.fps

    def extended(self, n_frames: int) -> "Schedule":
        """The same schedule cut to, or lengthened to ``n_frames`` by holding the last frame."""
        src = self.source[:n_frames]
        if n_frames > len(src):
            src = np.r_[src, np.full(n_frames - len(src), src[-1] if len(src) else 0, dtype=np.int64)]
        return Schedule(self.fps, src, self.times)


def presentation_times(stream: FapStream) -> np.ndarray:
    """Seconds from the first frame; raises on time running backwards."""
    t = np.asarray(stream.timestamps, float)
    if not len(t):
        return t
    rel = t - t[0]
    back = np.flatnonzero(np.diff(rel) < -_EPS)
    if len(back):
        k = int(back[0]) + 1
        raise RenderError(f"timestamp {t[k]:.3f} s is before the previous frame's {t[k - 1]:.3f} s",
                          where=f"frame {k}", hint="the stream's time codes go backwards; re-encode it")
    return rel


def schedule(stream: FapStream, fps: float | None = None) -> Schedule:
    """Output frames at ``fps`` (default: the stream's) covering the stream's duration."""
    if not len(stream):
        raise RenderError("the stream has no frames to show", where="stream")
    rate = float(fps or stream.fps)
    if not (0 < rate <= 1000) or math.isnan(rate):
        raise RenderError(f"frame rate {rate} is not usable", hint="a rate between 0 and 1000 frames/s")
    times = presentation_times(stream)
    end = times[-1] + (int(stream.skip[-1]) + 1) / stream.fps
    n_out = max(int(math.ceil(end * rate - 1e-6)), 1)
    ticks = np.arange(n_out) / rate
    source = np.searchsorted(times, ticks + _EPS, side="right") - 1
    return Schedule(rate, np.maximum(source, 0).astype(np.int64), times)
