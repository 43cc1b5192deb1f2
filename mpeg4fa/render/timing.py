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
MAX_OUTPUT_SECONDS = 12 * 3600.0
"""Longest output a schedule makes: a player or exporter renders (or resamples) every tick of it, so a stream whose
time codes jump by hours (a 150-byte .fap whose second frame is numbered 2000000: 22 h at 25 fps) would otherwise
render for a day or fill memory. Real streams last minutes to a few hours."""
MAX_HELD_FRAMES = 1_000_000
"""Most output frames a schedule makes where they are all held in memory (an export's resampled weights: 11 h at
25 frames/s, 65 min at 255); a player streams its frames and takes the time limit alone."""


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


def schedule(stream: FapStream, fps: float | None = None, max_frames: int | None = None) -> Schedule:
    """Output frames at ``fps`` (default: the stream's) covering the stream's duration: at most
    :data:`MAX_OUTPUT_SECONDS` of them, and ``max_frames`` where given (:data:`MAX_HELD_FRAMES`)."""
    if not len(stream):
        raise RenderError("the stream has no frames to show", where="stream")
    rate = float(fps or stream.fps)
    if not (0 < rate <= 1000) or math.isnan(rate):
        raise RenderError(f"frame rate {rate} is not usable", hint="a rate between 0 and 1000 frames/s")
    times = presentation_times(stream)
    end = times[-1] + (int(stream.skip[-1]) + 1) / stream.fps
    within = end <= MAX_OUTPUT_SECONDS  # (False for an infinite or NaN time too)
    n_out = max(int(math.ceil(end * rate - 1e-6)), 1) if within else 0
    if not within or (max_frames is not None and n_out > max_frames):
        gaps = np.diff(times)
        k = int(np.argmax(gaps)) + 1 if len(gaps) else 0
        widest = (f"; frame {k} comes {_span(gaps[k - 1])} after frame {k - 1}: a frame number or time code is "
                  "probably wrong" if len(gaps) and gaps[k - 1] > end / 2 else "")
        made = f", {n_out:,} output frames at {rate:g} frames/s" if within else ""
        most = (f"at most {_span(MAX_OUTPUT_SECONDS)} is made" if not within else
                f"at most {max_frames:,} output frames are made here; lower --fps")
        raise RenderError(f"the stream's {len(times)} frames span {_span(end)}{made}{widest}", where="stream",
                          hint=f"{most}, or fix the stream's frame numbers")
    ticks = np.arange(n_out) / rate
    source = np.searchsorted(times, ticks + _EPS, side="right") - 1
    return Schedule(rate, np.maximum(source, 0).astype(np.int64), times)


def _span(seconds: float) -> str:
    """``seconds`` as people read a length: 4.2 s, 12 min 30 s, 22 h 13 min (past a million hours, or not a number,
    as a number of seconds: 1e+300 s)."""
    if not seconds < 3.6e9:
        return f"{seconds:.3g} s"
    if seconds < 60:
        return f"{seconds:.3g} s"
    minutes = int(seconds // 60)
    if minutes < 60:
        return f"{minutes} min {int(seconds - 60 * minutes)} s"
    return f"{minutes // 60} h {minutes % 60} min"
