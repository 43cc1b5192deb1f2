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


def periodicity(x: np.ndarray, rate: int, hop: float = HOP) -> tuple[np.ndarray, np.ndarray]:
    """Per ``hop`` frame of ``x`` (float mono): the normalised autocorrelation peak over pitch lags
    (0 for a silent frame), and the pitch (Hz) at that peak."""
    y = resample(x, rate, RATE)
    step = int(round(hop * RATE))
    frames = max(1, int(np.ceil(len(x) / rate / hop)))
    pad = np.zeros(frames * step + WINDOW)
    pad[WINDOW // 2:WINDOW // 2 + min(len(y), len(pad) - WINDOW // 2)] = y[:len(pad) - WINDOW // 2]
    peak = np.zeros(frames)
    pitch = np.zeros(frames)
    block = 4096  # frames at a time: memory of a block, whatever the length
    lo, hi = LAGS
    for first in range(0, frames, block):
        n = min(block, frames - first)
        idx = (first + np.arange(n))[:, None] * step + np.arange(WINDOW)[None, :]
        w = pad[idx]
        w = w - w.mean(axis=1, keepdims=True)
        spec = np.fft.rfft(w, 2 * WINDOW, axis=1)
        ac = np.fft.irfft(spec.real ** 2 + spec.imag ** 2, axis=1)[:, :hi + 1]
        energy = ac[:, 0]
        # unbiased: each lag's sum over fewer products, scaled back to the window
        ac = ac[:, lo:hi + 1] * (WINDOW / (WINDOW - np.arange(lo, hi + 1)))[None, :]
        best = np.argmax(ac, axis=1)
        value = ac[np.arange(n), best] / np.maximum(energy, 1e-12)
        value[energy < 1e-9] = 0.0
        peak[first:first + n] = np.clip(value, 0.0, 1.0)
        pitch[first:first + n] = RATE / (lo + best)
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
