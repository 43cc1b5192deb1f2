"""Lip sync check: does a decoded stream's mouth open when its speech is loud?

A speech stream (visemes, or low-level lip and jaw FAPs) is made for one piece
of audio. If the two belong together, the inner-lip gap of the posed face rises
and falls with the short-time energy of the speech: the mouth is nearly closed
in pauses and open on vowels. This module measures both per stream frame and
correlates them, also at small frame shifts, so that a stream that is late or
early against its audio shows up as a best lag other than 0.

* :func:`mouth_opening`: inner-lip gap (feature point 2.2 above 2.3) in mm;
* :func:`speech_energy`: short-time RMS of the speech in dB (or linear) around
  each frame time;
* :func:`lipsync_report`: the two, correlated at lags ``-max_lag..+max_lag``.

The figure is a plausibility check, not a quality score: energy follows
loudness, the mouth follows the phones, and closed-lip consonants (p, b, m)
are loud while the lips touch. A correlation well above 0 means the stream
moves with its speech; a best lag far from 0 means it is shifted. Short clips
that all start in silence share an onset that alone gives a positive r: to
judge one stream, compare with its mouth against some other clip's audio.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from mpeg4fa.decoded import resolve
from mpeg4fa.face.model import FaceModel
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.render.audio import Audio

UPPER_INNER_LIP = "2.2"
LOWER_INNER_LIP = "2.3"

DEFAULT_FLOOR_DB = -60.0
"""Energy floor in dB full scale. Recorded silence sits anywhere from -90 to -60 dBFS
(dither, room noise); those differences say nothing about the mouth, so they are
cut off rather than left to weigh on the correlation."""

DEFAULT_MAX_LAG = 5
"""Frames searched either way (200 ms at 25 fps: more than any plausible A/V offset of a
stream made for its audio, less than a syllable pattern repeating)."""


def mouth_opening(face: FaceModel, stream: FapStream) -> np.ndarray:
    """``(n,)`` inner-lip gap in mm at every frame: y of 2.2 minus y of 2.3 on the posed face.

    The frames' 68 FAP values are resolved once for the whole stream (as
    :meth:`FaceModel.animate` does) and each distinct frame is posed once: speech
    streams repeat frames (held visemes, pauses), so this is the same result as
    posing every frame, for less work. Negative values mean the lips press into
    each other (bilabial visemes).
    """
    labels = list(face.mesh.fp_labels)
    upper, lower = labels.index(UPPER_INNER_LIP), labels.index(LOWER_INNER_LIP)
    values = resolve(stream)
    if not len(values):
        return np.zeros(0)
    distinct, inverse = np.unique(values, axis=0, return_inverse=True)
    gaps = np.empty(len(distinct))
    for k, row in enumerate(distinct):
        points = face.deform(row).feature_points
        gaps[k] = points[upper, 1] - points[lower, 1]
    return gaps[np.asarray(inverse).reshape(-1)]


def on_frame_grid(stream: FapStream, per_frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Frame times from the first frame (``k / fps``) and ``per_frame`` rows with skipped frames repeated.

    A skipped frame shows the frame before it again; lags and peaks are counted in frames, so
    they need every frame period present.
    """
    repeats = np.asarray(stream.skip, dtype=np.int64) + 1
    rows = np.repeat(np.asarray(per_frame), repeats, axis=0)
    return np.arange(len(rows)) / float(stream.fps), rows


def speech_energy(audio: Audio, times: np.ndarray, window: float, *, db: bool = True,
                  floor_db: float = DEFAULT_FLOOR_DB) -> np.ndarray:
    """Short-time RMS of the mono speech in a ``window``-second window centred on each time.

    dB by default, because the mouth does not open ten times wider on a vowel ten
    times more powerful: opening follows loudness, which is logarithmic. In linear
    RMS a handful of loud vowels would set the correlation, while in dB speech
    against pause and soft against loud syllables all count. The dB values are
    ``20 log10(rms)`` clipped below at ``floor_db``; with ``db=False`` the plain RMS
    (same units as the samples) comes back.

    Every window has the same number of samples (``round(window * rate)``, at least
    one). A window that runs past either end of the audio gets the RMS of the
    part inside; one wholly outside gets 0 (linear) or ``floor_db``. Computed for
    all times at once from a cumulative sum of squares.
    """
    if window <= 0:
        raise ValueError(f"the energy window must be positive, got {window}")
    times = np.asarray(times, dtype=np.float64)
    x = audio.mono().astype(np.float64)
    n = len(x)
    sums = np.concatenate(([0.0], np.cumsum(x * x)))
    size = max(1, int(round(window * audio.rate)))
    start = np.round(times * audio.rate).astype(np.int64) - size // 2
    lo = np.clip(start, 0, n)
    hi = np.clip(start + size, 0, n)
    count = hi - lo
    # differences of a long cumulative sum can dip a hair below 0 in silence
    power = np.maximum(sums[hi] - sums[lo], 0.0) / np.maximum(count, 1)
    rms = np.sqrt(np.where(count > 0, power, 0.0))
    if not db:
        return rms
    with np.errstate(divide="ignore"):
        level = 20.0 * np.log10(rms)
    return np.maximum(level, floor_db)


def pearson(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation of two equal-length series; NaN when either is constant or shorter than 2
    (no variation, nothing to correlate: better said than reported as 0)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape != b.shape:
        raise ValueError(f"series of different shapes {a.shape} and {b.shape}")
    if len(a) < 2 or np.ptp(a) == 0 or np.ptp(b) == 0:
        return float("nan")
    da, db_ = a - a.mean(), b - b.mean()
    r = (da * db_).sum() / np.sqrt((da * da).sum() * (db_ * db_).sum())
    return float(np.clip(r, -1.0, 1.0))


def lagged_correlations(opening: np.ndarray, energy: np.ndarray, max_lag: int = DEFAULT_MAX_LAG) -> np.ndarray:
    """Pearson correlation at every lag ``-max_lag..+max_lag`` (index ``lag + max_lag``).

    Lag ``L`` pairs the mouth at frame ``k`` with the audio at frame ``k + L``, over
    the frames where both exist: a positive lag means the mouth *leads* the audio
    (it opens ``L`` frames before the sound), a negative one that it lags behind.
    """
    opening = np.asarray(opening, dtype=np.float64)
    energy = np.asarray(energy, dtype=np.float64)
    n = len(opening)
    out = np.full(2 * max_lag + 1, np.nan)
    for lag in range(-max_lag, max_lag + 1):
        if lag >= 0:
            a, b = opening[: n - lag], energy[lag:]
        else:
            a, b = opening[-lag:], energy[: n + lag]
        out[lag + max_lag] = pearson(a, b)
    return out


def best_lag(correlations: np.ndarray) -> int:
    """The lag of the highest correlation (ties: the one nearest 0); 0 when all are NaN."""
    correlations = np.asarray(correlations, dtype=np.float64)
    max_lag = (len(correlations) - 1) // 2
    lags = np.arange(-max_lag, max_lag + 1)
    if np.isnan(correlations).all():
        return 0
    score = np.where(np.isnan(correlations), -np.inf, correlations)
    top = np.flatnonzero(score == score.max())
    return int(lags[top[np.argmin(np.abs(lags[top]))]])


@dataclass
class LipSyncReport:
    """How one stream's mouth follows its speech.

    ``correlation`` is Pearson's r between inner-lip gap and speech energy at lag
    0; ``best_lag_frames`` is the lag in ``-max_lag..+max_lag`` with the highest r
    (``best_correlation``). **Positive lag = the mouth leads the audio** (the mouth
    at frame k matches the sound at frame k + lag); negative = the mouth is late.
    Only frames whose time lies inside the audio are compared (``n_compared``):
    frames past the end of the speech would pair a moving mouth with silence
    that is not there, only missing. ``n_frames`` counts the frames shown, skipped
    ones included.
    """

    name: str
    n_frames: int
    fps: float
    stream_duration: float
    audio_duration: float
    correlation: float
    best_lag_frames: int
    best_correlation: float
    n_compared: int = 0
    window: float = 0.0
    max_lag: int = DEFAULT_MAX_LAG
    lag_correlations: list[float] = field(default_factory=list)
    """r at lags ``-max_lag..+max_lag`` in order."""

    @property
    def duration_mismatch(self) -> float:
        """Audio minus stream duration in seconds (positive: the speech runs on after the last frame)."""
        return self.audio_duration - self.stream_duration

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready values (NaN becomes None: JSON has no NaN)."""
        def clean(v: Any) -> Any:
            if isinstance(v, float) and np.isnan(v):
                return None
            if isinstance(v, list):
                return [clean(x) for x in v]
            return v

        out = {k: clean(v) for k, v in asdict(self).items()}
        out["duration_mismatch"] = clean(self.duration_mismatch)
        return out


def lipsync_report(face: FaceModel, stream: FapStream, audio: Audio, name: str = "", *,
                   window: float | None = None, max_lag: int = DEFAULT_MAX_LAG, db: bool = True,
                   floor_db: float = DEFAULT_FLOOR_DB, opening: np.ndarray | None = None) -> LipSyncReport:
    """Correlate ``stream``'s mouth opening on ``face`` with the energy of ``audio``.

    The audio is taken to start with the stream's first frame (as playback aligns
    them). ``window`` defaults to one frame period, so that each frame's energy
    covers the sound around it without overlapping its neighbours'. Skipped frames
    are put back on the frame grid (:func:`on_frame_grid`); ``opening`` may give
    the mouth opening on that grid when the caller has it already.
    """
    fps = float(stream.fps)
    if window is None:
        window = 1.0 / fps
    if opening is None:
        times, opening = on_frame_grid(stream, mouth_opening(face, stream))
    else:
        times = np.arange(len(opening)) / fps
        if len(opening) != int((np.asarray(stream.skip) + 1).sum()):
            raise ValueError(f"opening has {len(opening)} values, the stream {len(stream)} frames on its grid")
    opening = np.asarray(opening, dtype=np.float64)
    inside = times < audio.duration
    energy = speech_energy(audio, times[inside], window, db=db, floor_db=floor_db)
    lags = lagged_correlations(opening[inside], energy, max_lag)
    lag = best_lag(lags)
    return LipSyncReport(
        name=name, n_frames=len(times), fps=fps, stream_duration=float(stream.duration),
        audio_duration=float(audio.duration), correlation=float(lags[max_lag]), best_lag_frames=lag,
        best_correlation=float(lags[lag + max_lag]), n_compared=int(inside.sum()), window=float(window),
        max_lag=max_lag, lag_correlations=[float(r) for r in lags],
    )
