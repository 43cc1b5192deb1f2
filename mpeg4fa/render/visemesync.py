"""Viseme timing read back from a decoded stream: when each viseme peaks, when the lips shut.

:mod:`.lipsync` asks whether the mouth opens with the sound; this module asks
whether each viseme arrives on time. Given the decoded stream and the spans the
encoder was told (phoneme onsets and ends, e.g. espeak's events or an aligner's),
it measures on the frames the viewer sees:

* :func:`viseme_weights`: how much of each span's viseme every frame shows. A
  decoded frame is a blend of a few neighbouring visemes (two in a transition,
  one while a shape is held), so each frame's FAPs are fitted, non-negatively,
  with the profiles of the spans around it; the coefficient of the span's own
  viseme is its weight (1 = its full shape).
* :func:`viseme_peaks`: the time each weight reaches its top, and where that
  falls inside the phoneme (0 = onset, 1 = end). Lip sync wants the shape near
  the acoustic onset: a mouth that reaches each shape at the end of its phoneme
  trails the voice by most of a phoneme.
* :func:`closure_offsets`: bilabial closures (MPEG-4 ``PP``, Chinese ``bpm``)
  must be *seen* shut, close to the consonant's onset: the first frame whose
  inner-lip gap (feature point 2.2 above 2.3) is closed, minus the onset.
* :func:`measure_sync`: all of it plus the energy correlation of
  :func:`.lipsync.lipsync_report`, as one :class:`SyncFigures`, optionally also
  against an independent aligner's phone onsets (:mod:`.phonealign`).

Skipped frames (an encoder may skip repeats) are put back on the frame grid
first, so frame ``k`` is at ``k / fps`` from the first frame.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any, Protocol

import numpy as np
from scipy.optimize import nnls

from mpeg4fa.decoded import resolve
from mpeg4fa.face.model import FaceModel
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.render.audio import Audio
from mpeg4fa.render.lipsync import lipsync_report, mouth_opening, on_frame_grid
from mpeg4fa.render.phonealign import AlignedPhone, aligned_offsets, aligned_onsets
from mpeg4fa.spec.profiles import VISEME_PROFILES

CLOSURES = frozenset({("mpeg4", "PP"), ("zh", "bpm")})
"""Visemes whose lips touch: the ones a viewer notices when they are missed or late."""

PEAK_TOLERANCE = 0.03
"""A frame within this weight of the top counts as at the top: quantised FAPs move a fitted
weight by about 1 %, so the first frame of a held shape is not lost to rounding noise."""

NEIGHBOURS = 2
"""Spans either side whose profiles enter the fit (the mouth blends at most the two around a
boundary, but the window reaches into the neighbours' own transitions)."""

WINDOW = 0.25
"""Seconds either side of a span beyond which a shape is not taken for this span's."""


class TimedViseme(Protocol):
    """What a span must have: e.g. :class:`mpeg4fa.speech.timeline.VisemeSpan` or an utterance timing."""

    viseme: str
    start: float
    end: float
    set: str


def _profile(span: TimedViseme) -> np.ndarray:
    try:
        return VISEME_PROFILES[span.set][span.viseme].astype(np.float64)
    except KeyError:
        raise ValueError(f"{span.set}:{span.viseme} is not a known viseme") from None


def _bounds(spans: Sequence[TimedViseme]) -> tuple[np.ndarray, np.ndarray]:
    starts = np.array([float(s.start) for s in spans])
    ends = np.array([float(s.end) for s in spans])
    if len(spans) and (np.any(ends <= starts) or np.any(starts[1:] < ends[:-1] - 1e-9)):
        raise ValueError("spans must be in time order, each with start < end, not overlapping")
    return starts, ends


def viseme_weights(values: np.ndarray, times: np.ndarray, spans: Sequence[TimedViseme]) -> np.ndarray:
    """``(m, n)`` weight of span k's viseme at each of the ``n`` frames; NaN outside its window.

    ``values`` are the frames' resolved FAPs (n, 68). Span k's window runs from the middle
    of span k-1 to the middle of span k+1 (at most :data:`WINDOW` s beyond the span): there
    the mouth is between k-1, k and k+1. Each frame in it is fitted by non-negative least
    squares with the distinct profiles of spans k-2..k+2 (a span naming the same viseme as k
    shares k's column, so a repeated shape is not split between two columns).
    """
    values = np.asarray(values, dtype=np.float64)
    times = np.asarray(times, dtype=np.float64)
    starts, ends = _bounds(spans)
    mids = (starts + ends) / 2
    out = np.full((len(spans), len(times)), np.nan)
    for k, span in enumerate(spans):
        lo = max(mids[k - 1] if k > 0 else -np.inf, starts[k] - WINDOW)
        hi = min(mids[k + 1] if k + 1 < len(spans) else np.inf, ends[k] + WINDOW)
        frames = np.flatnonzero((times >= lo) & (times <= hi))
        if not len(frames):
            continue
        keys = [(span.set, span.viseme)]
        columns = [_profile(span)]
        for j in range(max(0, k - NEIGHBOURS), min(len(spans), k + NEIGHBOURS + 1)):
            key = (spans[j].set, spans[j].viseme)
            p = _profile(spans[j])
            if key not in keys and np.abs(p).max() > 0:
                keys.append(key)
                columns.append(p)
        basis = np.stack(columns, axis=1)
        used = np.abs(basis).max(axis=1) > 0
        basis = basis[used]
        out[k, frames] = [nnls(basis, values[f, used])[0][0] for f in frames]
    return out


@dataclass(frozen=True)
class VisemePeaks:
    """When each span's viseme reaches its top weight, against the span (seconds)."""

    start: np.ndarray
    end: np.ndarray
    peak: np.ndarray       # NaN where the span had no frame in its window
    top: np.ndarray        # the largest weight reached (1 = the full shape)
    frame_period: float

    @property
    def relative(self) -> np.ndarray:
        """Peak position in the phoneme: 0 at its onset, 1 at its end."""
        return (self.peak - self.start) / (self.end - self.start)

    @property
    def in_first_half(self) -> np.ndarray:
        """Peak between the onset and the middle of the phoneme. Up to one frame before the onset
        still counts: a move arrives with slope 0, so the frame before the arrival already reads
        within :data:`PEAK_TOLERANCE` of the top."""
        return (self.peak >= self.start - self.frame_period - 1e-9) & (self.peak <= (self.start + self.end) / 2)

    @property
    def first_half_fraction(self) -> float:
        return float(self.in_first_half.mean()) if len(self.peak) else float("nan")


def _refined(times: np.ndarray, w: np.ndarray, k: int) -> float:
    """Sub-frame peak of a lone top frame ``k``: the vertex of the parabola through it and its neighbours."""
    if k == 0 or k + 1 >= len(w) or not np.isfinite(w[k - 1:k + 2]).all():
        return float(times[k])
    a, b, c = w[k - 1], w[k], w[k + 1]
    curve = a - 2 * b + c
    if curve >= 0:
        return float(times[k])
    shift = float(np.clip(0.5 * (a - c) / curve, -0.5, 0.5))
    step = times[k + 1] - times[k] if shift > 0 else times[k] - times[k - 1]
    return float(times[k] + shift * step)


def viseme_peaks(weights: np.ndarray, times: np.ndarray, spans: Sequence[TimedViseme],
                 tolerance: float = PEAK_TOLERANCE) -> VisemePeaks:
    """The first frame at which each weight comes within ``tolerance`` of its top.

    A shape that is held shows the same weight over several frames: its peak is when it is
    first reached, not the middle of the hold. A lone top frame (both neighbours clearly
    lower) is refined to the vertex of a parabola, so a short viseme's peak is not rounded
    to the frame grid.
    """
    times = np.asarray(times, dtype=np.float64)
    starts, ends = _bounds(spans)
    peak = np.full(len(spans), np.nan)
    top = np.full(len(spans), np.nan)
    for k, w in enumerate(np.asarray(weights, dtype=np.float64)):
        if not np.isfinite(w).any():
            continue
        top[k] = np.nanmax(w)
        near = np.flatnonzero(np.nan_to_num(w, nan=-np.inf) >= top[k] - tolerance)
        first = int(near[0])
        lone = len(near) == 1 or near[1] != first + 1
        peak[k] = _refined(times, w, first) if lone else float(times[first])
    period = float(np.median(np.diff(times))) if len(times) > 1 else 0.0
    return VisemePeaks(starts, ends, peak, top, period)


@dataclass(frozen=True)
class ClosureTiming:
    """For each closure span: whether the lips are seen shut near the consonant's onset, and when first.

    ``near_onset``: some frame no further than ``tolerance`` from the onset shows the lips shut
    (a closure that starts a little early and lasts through the onset counts; one that comes
    late, or is never seen, does not). ``offset``: the first shut frame of the search window
    minus the onset (negative: shut before it; NaN: never shut).
    """

    onset: np.ndarray
    offset: np.ndarray
    near_onset: np.ndarray
    tolerance: float

    @property
    def missed(self) -> int:
        return int(np.isnan(self.offset).sum())

    @property
    def within_tolerance(self) -> float:
        return float(self.near_onset.mean()) if len(self.near_onset) else float("nan")


def closure_offsets(opening: np.ndarray, times: np.ndarray, spans: Sequence[TimedViseme],
                    onsets: np.ndarray | None = None, shut_mm: float = 0.0,
                    tolerance: float | None = None) -> ClosureTiming:
    """When the lips are seen shut (inner-lip gap <= ``shut_mm``) around each closure span.

    ``onsets`` (one per span, NaN to leave a span out) replace the spans' own starts as the
    consonant onsets, e.g. an aligner's. ``tolerance`` defaults to one frame period. The
    first shut frame is looked for from the middle of the span before (at most
    :data:`WINDOW` s before the onset) to one frame past the span's end.
    """
    opening = np.asarray(opening, dtype=np.float64)
    times = np.asarray(times, dtype=np.float64)
    starts, ends = _bounds(spans)
    ref = starts if onsets is None else np.asarray(onsets, dtype=np.float64)
    period = float(np.median(np.diff(times))) if len(times) > 1 else 0.0
    tol = period if tolerance is None else float(tolerance)
    chosen = [k for k, s in enumerate(spans) if (s.set, s.viseme) in CLOSURES and np.isfinite(ref[k])]
    offsets = np.full(len(chosen), np.nan)
    near = np.zeros(len(chosen), dtype=bool)
    shut = opening <= shut_mm
    for i, k in enumerate(chosen):
        before = (starts[k - 1] + ends[k - 1]) / 2 if k > 0 else -np.inf
        lo = max(before, ref[k] - WINDOW, starts[k] - WINDOW)
        hi = max(ends[k], ref[k]) + period
        found = np.flatnonzero((times >= lo) & (times <= hi) & shut)
        if len(found):
            offsets[i] = times[found[0]] - ref[k]
        near[i] = bool(shut[np.abs(times - ref[k]) <= tol + 1e-9].any())
    return ClosureTiming(ref[chosen], offsets, near, tol)


@dataclass
class SyncFigures:
    """The lip sync figures of one decoded stream against its spans and audio (seconds, frames).

    The ``aligned_*`` figures compare with an independent aligner's phone onsets
    (:mod:`.phonealign`); NaN when no phones were given.
    """

    name: str
    fps: float
    n_visemes: int
    first_half_fraction: float       # peaks between onset (a frame early counts) and middle
    median_relative_peak: float      # 0 = onset, 1 = end
    mean_peak_offset: float          # peak minus onset, seconds
    best_lag_frames: int             # energy correlation: positive = the mouth leads
    correlation: float               # r at lag 0
    best_correlation: float
    n_closures: int
    closures_within_frame: float     # shut at a frame within one frame of the onset
    closures_missed: int
    mean_closure_offset: float       # first shut frame minus onset, seconds (missed left out)
    n_aligned: int = 0               # spans paired with an aligned phone
    aligned_mean_offset: float = float("nan")   # peak minus aligned onset, seconds
    aligned_p95_offset: float = float("nan")    # 95th percentile of its size
    aligned_closures_within_frame: float = float("nan")
    aligned_offsets: list[float] = field(default_factory=list)  # each pair's peak - aligned onset

    def to_dict(self) -> dict[str, Any]:
        return {k: (None if isinstance(v, float) and np.isnan(v) else v) for k, v in asdict(self).items()}


def _nan_stat(f, x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(f(x)) if len(x) else float("nan")


def measure_sync(face: FaceModel, stream: FapStream, audio: Audio, spans: Sequence[TimedViseme],
                 name: str = "", phones: Sequence[AlignedPhone] | None = None) -> SyncFigures:
    """Decoded ``stream`` (resolved, posed on ``face``) against the ``spans`` it was made for, and, if
    ``phones`` (an aligner's, :func:`.phonealign.align_phones`) are given, against their onsets too.

    The spans' times are in the audio, which starts with the stream's first frame.
    """
    spans = sorted(spans, key=lambda s: s.start)
    times, values = on_frame_grid(stream, resolve(stream))
    _, opening = on_frame_grid(stream, mouth_opening(face, stream))
    peaks = viseme_peaks(viseme_weights(values, times, spans), times, spans)
    closures = closure_offsets(opening, times, spans)
    energy = lipsync_report(face, stream, audio, name=name, opening=opening)
    figures = SyncFigures(
        name=name, fps=float(stream.fps), n_visemes=len(spans),
        first_half_fraction=peaks.first_half_fraction,
        median_relative_peak=_nan_stat(np.median, peaks.relative),
        mean_peak_offset=_nan_stat(np.mean, peaks.peak - peaks.start),
        best_lag_frames=energy.best_lag_frames, correlation=energy.correlation,
        best_correlation=energy.best_correlation, n_closures=len(closures.offset),
        closures_within_frame=closures.within_tolerance, closures_missed=closures.missed,
        mean_closure_offset=_nan_stat(np.mean, closures.offset),
    )
    if phones is not None:
        visemes = [s.viseme if s.set == "mpeg4" else "" for s in spans]
        aligned = aligned_offsets(visemes, peaks.start, peaks.peak, phones)
        onsets = aligned_onsets(visemes, peaks.start, phones)
        figures.n_aligned = len(aligned.offsets)
        figures.aligned_mean_offset, figures.aligned_p95_offset = aligned.mean, aligned.p95
        figures.aligned_offsets = [float(x) for x in aligned.offsets]
        figures.aligned_closures_within_frame = closure_offsets(opening, times, spans, onsets).within_tolerance
    return figures
