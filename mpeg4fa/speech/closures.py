"""Stop consonants start at their closure, not at their release.

A stop (p, b, t, d, k, g) is a silence (the closure: lips or tongue shut, no
sound) followed by a burst (the release). espeak-ng starts the stop's phoneme
event at the release and books the closure's silence to the end of the phoneme
before it, so a mouth timed by the events closes its lips for a ``p`` some 40-60
ms after the sound has stopped (a forced aligner puts the onset at the silence;
see :mod:`mpeg4fa.render.phonealign`). The audio shows where the closure is: the
silent stretch right before the stop. :func:`stop_closures` moves each stop's
start back to the start of that silence, shortening the phoneme before it.

A breathy voice (espeak-ng's +f2..+f5; a recording's breath or room noise) fills
the closure with noise above the silence threshold; where no block is silent the
closure starts at the last sharp fall of level before the stop (:data:`DROP_DB`).

Only the spans of stop visemes move, and only over silence (or breath after a
sharp fall) that follows sound inside the previous phoneme: a pause (the whole previous phoneme silent,
or no audio at all as with the silent estimator) is left as it is.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from mpeg4fa.speech.tts.base import Speech
from mpeg4fa.speech.utterance import Timing
from mpeg4fa.speech.visemes import PAUSE

STOP_VISEMES = frozenset({("mpeg4", "PP"), ("mpeg4", "DD"), ("mpeg4", "kk"),
                          ("zh", "bpm"), ("zh", "dtnl"), ("zh", "gkh")})
"""Visemes whose phonemes include stops (a nasal m or n has no silence before it and stays put)."""

SILENCE_DB = -50.0
"""RMS (dBFS) below which a block is a closure's silence: espeak-ng's closures are digital zero,
recorded ones sit at the noise floor, speech is above -40."""

BLOCK = 0.005
"""Seconds per RMS block: fine enough to place the closure within a tenth of a frame."""

LONGEST = 0.15
"""The longest closure taken (s): longer silences are pauses, not closures."""

SHORTEST = 0.01
"""Shorter silences are not moved over (s): a dip between sounds, not a closure."""

KEEP = 0.02
"""What the previous phoneme keeps at least (s)."""

DROP_DB = 8.0
"""A breathy closure: where no block is silent, the closure starts after the last block that stands this many dB
above the next block and above every block after it up to the stop (a sharp fall into breath noise, which
espeak-ng's breathy voices (+f2..+f5) put at -50..-36 dBFS in a closure; a vowel fading out falls 1-3 dB a block).
8: the smallest at which the plain voices' stops stay where their silence puts them (tools/closure_breath_check.py,
sentences of its own: stops off by > 15 ms in en-us+f2..f5 124 of 240 -> 21, none in the plain voices)."""


def _levels(samples: np.ndarray, rate: int, start: float, end: float) -> tuple[np.ndarray, int]:
    """RMS level (dBFS) of the whole blocks that end at ``end`` inside [start, end), at most LONGEST + 1 of
    them, last block first; and the block length in samples."""
    block = max(1, int(round(BLOCK * rate)))
    stop = int(round(end * rate))
    first = max(0, int(round(start * rate)))
    n = min((stop - first) // block, int(LONGEST / BLOCK) + 1)
    if n <= 0:
        return np.zeros(0), block
    tail = samples[stop - n * block:stop].astype(np.float64).reshape(n, block)[::-1]
    return 10 * np.log10(np.maximum((tail * tail).mean(axis=1), 1e-20)), block


def _silent_tail(samples: np.ndarray, rate: int, start: float, end: float) -> float:
    """Seconds of silence at the end of [start, end), in whole blocks (0 if none or all silent)."""
    level, block = _levels(samples, rate, start, end)
    loud = np.flatnonzero(level >= SILENCE_DB)
    if not len(loud):  # all silent: a pause, not a closure
        return 0.0
    return float(loud[0] * block / rate)


def _breathy_tail(samples: np.ndarray, rate: int, start: float, end: float) -> float:
    """Seconds from the last sharp fall of level (:data:`DROP_DB`) to ``end`` (0 if none)."""
    level, block = _levels(samples, rate, start, end)
    if len(level) < 2:
        return 0.0
    after = np.maximum.accumulate(level)[:-1]  # after[i]: the loudest block from the stop back to block i
    fall = (level[1:] - after >= DROP_DB) & (level[1:] >= SILENCE_DB)  # block i + 1 stands above all after it
    hit = np.flatnonzero(fall)
    return float((hit[0] + 1) * block / rate) if len(hit) else 0.0


def _closure_tail(samples: np.ndarray, rate: int, start: float, end: float) -> float:
    """Seconds of closure at the end of [start, end): its silence, or where none, its breath after a sharp fall."""
    silence = _silent_tail(samples, rate, start, end)
    return silence if silence >= SHORTEST else _breathy_tail(samples, rate, start, end)


def stop_closures(timings: Sequence[Timing], speech: Speech) -> tuple[Timing, ...]:
    """``timings`` with each stop moved back over the silence before it (see the module docstring)."""
    out = list(timings)
    samples = speech.samples.astype(np.float64) / 32768.0
    order = sorted((i for i, t in enumerate(out) if t.end > t.start), key=lambda i: out[i].start)
    for prev_i, this_i in zip(order, order[1:]):
        prev, this = out[prev_i], out[this_i]
        if (this.set, this.viseme) not in STOP_VISEMES or prev.viseme == PAUSE:
            continue
        if abs(prev.end - this.start) > 1e-6 or prev.end - prev.start <= KEEP:
            continue
        silence = min(_closure_tail(samples, speech.rate, prev.start, this.start), LONGEST)
        silence = min(silence, this.start - prev.start - KEEP)
        if silence < SHORTEST:
            continue
        onset = this.start - silence
        out[prev_i] = replace(prev, end=onset)
        out[this_i] = replace(this, start=onset)
    return tuple(out)
