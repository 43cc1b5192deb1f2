"""Voice activity of a recording, 10 ms frame by frame: where a mouth should move at all.

A recogniser names *something* for every stretch of sound: pocketsphinx's phone loop hears phones in
white noise and in music, and its word search hears words. So speech is gated here first, on three
measures per frame of 10 ms (:data:`HOP`):

* **level**: loud enough above the recording's own noise floor (the aligner's rule,
  :func:`mpeg4fa.speech.align.recording.speech_frames`) and above :data:`FLOOR_DBFS`;
* **periodicity**: the peak of the normalised autocorrelation over pitch lags of 2.5-16 ms (62-400 Hz),
  on 32 ms windows at 8 kHz. Voiced speech (vowels, nasals, voiced consonants) reaches 0.5-0.95; white
  noise stays near 0.15 (the peak of ~100 lags of a 256-sample noise correlation). Noise, breath and
  silence are never periodic;
* **steadiness**: a note of music is periodic too, but its pitch holds still; a speaking voice glides.
  Where, within a second, a third or more of the voiced frames keep their pitch (within
  :data:`STEADY_CENTS` over :data:`STEADY_SECONDS`), it is music (or singing), not speech.

Speech is then voiced, unsteady, loud-enough frames, widened by :data:`REACH` on either side (the
unvoiced consonants next to the vowels: s, t, f, h, and the silent closure of a stop; a consonant
cluster before a vowel takes ~150 ms), and kept only where at least :data:`MIN_VOICED` seconds of such
frames come together (a click or a single periodic blip is not a syllable).
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.speech.align.recording import HOP, frame_levels, resample

RATE = 8000
"""Sample rate the periodicity is measured at (pitch needs no more)."""
WINDOW = 256
"""Samples per periodicity window at :data:`RATE` (32 ms: two periods of a 62 Hz voice)."""
LAGS = (20, 128)
"""Pitch lags searched, in samples at :data:`RATE`: 2.5-16 ms, 400-62 Hz."""
PEAK_SHARE = 0.9
"""A lag whose autocorrelation is this share of the best is the period, if it is the shortest such
(:func:`lag_peaks`)."""
PERIODIC = 0.45
"""Normalised autocorrelation peak above which a frame is voiced."""
FLOOR_DBFS = -55.0
"""No frame quieter than this is speech, however quiet the recording."""
STEADY_CENTS = 15.0
"""A pitch that moves less than this (cents) ..."""
STEADY_SECONDS = 0.05
"""... over this long is held ..."""
MUSIC_WINDOW = 1.0
MUSIC_SHARE = 0.25
"""... and where that many of the voiced frames of a second hold their pitch, it is music. Measured
(2026-12-05): the synthetic music of :mod:`.signals` 0.50-0.53; espeak-ng English and Spanish 0.06-0.12
(at 0.2 a flat Hindi voice lost a sixth of its speech)."""
REACH = 0.15
"""Seconds of unvoiced sound kept on each side of voiced speech (its consonants)."""
MIN_VOICED = 0.08
"""Fewest seconds of voiced frames in a row that count as speech (a vowel lasts longer; a note's onset
before the steadiness test catches it often does not)."""


def lag_peaks(windows: np.ndarray, lo: int, hi: int, shortest: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Per row of ``windows`` (samples): the normalised autocorrelation's peak over lags ``lo..hi``
    (unbiased: each lag's sum over fewer products scaled back to the window; 0 for a silent row), and
    the lag taken for the period: the best, or (``shortest``) the shortest local peak within
    :data:`PEAK_SHARE` of the best, placed between whole lags. A pure tone's autocorrelation is as high at every multiple of its
    period, so the best lag alone jumps between them from frame to frame and a held note looks like a
    gliding voice; the recording path's music test forgives those jumps over a second
    (:func:`_held`), the live one, deciding on 0.12 s, cannot."""
    size = windows.shape[1]
    w = windows - windows.mean(axis=1, keepdims=True)
    spec = np.fft.rfft(w, 2 * size, axis=1)
    ac = np.fft.irfft(spec.real ** 2 + spec.imag ** 2, axis=1)[:, :hi + 2]
    energy = ac[:, 0]
    lags = np.arange(lo - 1, hi + 2)
    ac = ac[:, lo - 1:hi + 2] * (size / (size - lags))[None, :] / np.maximum(energy, 1e-12)[:, None]
    inner = ac[:, 1:-1]
    best = inner.max(axis=1)
    first = np.argmax(inner, axis=1)
    value = np.where(energy < 1e-9, 0.0, np.clip(best, 0.0, 1.0))
    if not shortest:
        return value, lo + first
    peaks = (inner >= ac[:, :-2]) & (inner >= ac[:, 2:]) & (inner >= PEAK_SHARE * best[:, None])
    first = np.where(peaks.any(axis=1), np.argmax(peaks, axis=1), first)
    # the peak between lags (a parabola through it and its neighbours): a whole lag is 5-15 cents at a
    # voice's pitch, so whole lags make a slowly gliding voice look held for several frames
    rows = np.arange(len(first))
    a, b, c = ac[rows, first], ac[rows, first + 1], ac[rows, first + 2]
    bend = a - 2 * b + c
    shift = np.where(bend < -1e-12, 0.5 * (a - c) / np.where(bend < -1e-12, bend, -1.0), 0.0)
    return value, lo + first + np.clip(shift, -0.5, 0.5)


def periodicity(x: np.ndarray, rate: int, hop: float = HOP) -> tuple[np.ndarray, np.ndarray]:
    """Per ``hop`` frame of ``x`` (float mono): the normalised autocorrelation peak over pitch lags
    (0 for a silent frame), and the pitch (Hz) at its period (:func:`lag_peaks`)."""
    y = resample(x, rate, RATE)
    step = int(round(hop * RATE))
    frames = max(1, int(np.ceil(len(x) / rate / hop)))
    pad = np.zeros(frames * step + WINDOW)
    pad[WINDOW // 2:WINDOW // 2 + min(len(y), len(pad) - WINDOW // 2)] = y[:len(pad) - WINDOW // 2]
    peak = np.zeros(frames)
    pitch = np.zeros(frames)
    block = 4096  # frames at a time: memory of a block, whatever the length
    for first in range(0, frames, block):
        n = min(block, frames - first)
        idx = (first + np.arange(n))[:, None] * step + np.arange(WINDOW)[None, :]
        peak[first:first + n], lag = lag_peaks(pad[idx], *LAGS)
        pitch[first:first + n] = RATE / lag
    return peak, pitch


def _runs_at_least(mask: np.ndarray, frames: int) -> np.ndarray:
    """``mask`` with its runs of True shorter than ``frames`` cleared."""
    out = mask.copy()
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    for a, b in zip(edges[::2], edges[1::2]):
        if b - a < frames:
            out[a:b] = False
    return out


def _widen(mask: np.ndarray, frames: int) -> np.ndarray:
    """``mask`` grown by ``frames`` on both sides."""
    if frames <= 0 or not mask.any():
        return mask.copy()
    c = np.cumsum(np.r_[0, mask.astype(np.int32)])
    n = len(mask)
    i = np.arange(n)
    return (c[np.minimum(i + frames + 1, n)] - c[np.maximum(i - frames, 0)]) > 0


def _held(pitch: np.ndarray, voiced: np.ndarray, hop: float) -> np.ndarray:
    """Frames inside music: where, over :data:`MUSIC_WINDOW` around them, at least :data:`MUSIC_SHARE` of
    the voiced frames hold their pitch (within :data:`STEADY_CENTS`, octave slips of the picker forgiven)
    for :data:`STEADY_SECONDS`."""
    k = max(1, int(round(STEADY_SECONDS / hop)))
    if len(pitch) <= k:
        return np.zeros(len(pitch), dtype=bool)
    cents = 1200 * np.log2(np.maximum(pitch, 1.0))
    d = np.abs(cents[k:] - cents[:-k]) % 1200
    steady = np.zeros(len(pitch), dtype=bool)
    steady[k:] = (np.minimum(d, 1200 - d) < STEADY_CENTS) & voiced[k:] & voiced[:-k]
    w = np.ones(max(1, int(round(MUSIC_WINDOW / hop))))
    held = np.convolve(steady, w, "same")
    sung = np.convolve(voiced, w, "same")
    return held >= MUSIC_SHARE * np.maximum(sung, 1)


def voice_activity(x: np.ndarray, rate: int, hop: float = HOP) -> np.ndarray:
    """Which ``hop`` frames of ``x`` (float mono in [-1, 1]) are speech; see the module docstring."""
    from mpeg4fa.speech.align.recording import speech_frames

    levels = frame_levels(x, rate, hop)
    peak, pitch = periodicity(x, rate, hop)
    n = min(len(levels), len(peak))
    levels, peak, pitch = levels[:n], peak[:n], pitch[:n]
    if n == 0 or levels.max() < FLOOR_DBFS:
        return np.zeros(n, dtype=bool)
    loud = speech_frames(levels) & (levels >= FLOOR_DBFS)
    voiced = loud & (peak >= PERIODIC)
    held = _held(pitch, voiced, hop)
    voice = _runs_at_least(voiced & ~held, max(1, int(round(MIN_VOICED / hop))))
    return _widen(voice, int(round(REACH / hop)))  # quiet frames inside: a stop's closure is silent
