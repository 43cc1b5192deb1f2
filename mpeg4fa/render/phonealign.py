"""English phone onsets from an independent aligner (pocketsphinx), to check viseme timing against.

The encoder times visemes by espeak-ng's own phoneme events; measuring the result
against those same events cannot show where espeak's events and the sound part
ways. espeak-ng, for one, starts a voiceless stop's event at the release: the
silent closure before it is booked to the phoneme before. A forced aligner reads
the audio instead: the encoder's own pocketsphinx aligner (:mod:`mpeg4fa.speech.align.sphinx`,
the bundled en-us acoustic model and CMU dictionary) aligns the text to the speech; its
phones (ARPAbet) are mapped to MPEG-4 visemes and paired with the spans by :func:`match_phones`.
"""
from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mpeg4fa.render.audio import Audio
from mpeg4fa.render.errors import RenderError
from mpeg4fa.speech.align.sphinx import force_align, pcm16k, shared_decoder

FRAME = 0.01
"""pocketsphinx's frame step: alignment times are multiples of 10 ms."""

ARPABET_VISEMES: dict[str, frozenset[str]] = {
    phone: frozenset(visemes.split()) for phone, visemes in {
        "P": "PP", "B": "PP", "M": "PP", "F": "FF", "V": "FF", "TH": "TH", "DH": "TH",
        "T": "DD", "D": "DD", "K": "kk", "G": "kk", "NG": "kk", "HH": "kk",
        "CH": "CH", "JH": "CH", "SH": "CH", "ZH": "CH", "S": "SS", "Z": "SS",
        "N": "nn", "L": "nn", "R": "RR", "W": "ou", "Y": "ih",
        "AA": "AA oh", "AE": "AA", "AH": "AA E", "AO": "oh", "AW": "AA", "AY": "AA",
        "EH": "E", "ER": "E RR", "EY": "E", "IH": "ih E", "IY": "ih",
        "OW": "oh", "OY": "oh", "UH": "ou", "UW": "ou",
    }.items()
}
"""ARPAbet phone -> the MPEG-4 visemes espeak-ng's phonemes for it map to (spec/english_visemes.csv).
Two where the phone covers two espeak classes: AH is strut (AA) or schwa (E), AA is father (AA)
or lot (oh), IH is also reduced (E), ER r-coloured (E or RR)."""


@dataclass(frozen=True)
class AlignedPhone:
    """One phone of the forced alignment, in seconds from the start of the audio."""

    phone: str
    start: float
    end: float
    word: str


def alignment_words(text: str) -> list[str]:
    """The words to align: lower case, letters and apostrophes (the dictionary's spelling)."""
    return re.findall(r"[a-z']+", text.lower())


def align_phones(audio: Audio, text: str, *, seed: int = 0) -> list[AlignedPhone]:
    """Force-align ``text`` to ``audio``: every phone with its start and end (silences left out).

    Two passes as pocketsphinx does it: the words first, then the phones inside them.
    """
    words = alignment_words(text)
    if not words:
        raise RenderError("no words to align", where="phone alignment", hint="give the text that was spoken")
    decoder = shared_decoder()
    unknown = [w for w in words if decoder.lookup_word(w) is None]
    if unknown:
        raise RenderError(f"not in the CMU dictionary: {', '.join(sorted(set(unknown)))}",
                          where="phone alignment", hint="align text of dictionary words")
    try:
        alignment = force_align(pcm16k(audio.mono().astype(np.float64), int(audio.rate), seed), words)
    except RuntimeError as exc:
        raise RenderError(f"the aligner found no path through the text ({exc})", where="phone alignment",
                          hint="check the text is what the audio says") from None
    phones = []
    for word in alignment:
        spelling = re.sub(r"\(\d+\)$", "", word.name)  # "before(2)": the dictionary's second pronunciation
        for phone in word:
            name = phone.name
            if name in ARPABET_VISEMES:
                phones.append(AlignedPhone(name, phone.start * FRAME, (phone.start + phone.duration) * FRAME,
                                           spelling))
    return phones


def match_phones(visemes: Sequence[str], starts: np.ndarray, phones: Sequence[AlignedPhone],
                 max_distance: float = 0.15) -> list[tuple[int, int]]:
    """Pairs (span index, phone index) of one monotone alignment of the two sequences.

    Dynamic programming over both in time order: a pair is allowed when the phone's
    visemes include the span's and their onsets are within ``max_distance``; it costs
    ``|onset difference| / max_distance`` (0..1) and leaving an item unpaired costs 1,
    so the cheapest path pairs what it can and prefers nearer onsets. The two phone sets
    differ (espeak and the CMU dictionary disagree on some words), so not all are paired.
    """
    m, n = len(visemes), len(phones)
    onset = np.array([p.start for p in phones])
    cost = np.zeros((m + 1, n + 1))
    cost[:, 0] = np.arange(m + 1)
    cost[0, :] = np.arange(n + 1)
    move = np.zeros((m + 1, n + 1), dtype=np.int8)  # 0 pair, 1 skip span, 2 skip phone
    move[1:, 0], move[0, 1:] = 1, 2
    for i in range(1, m + 1):
        dist = np.abs(onset - starts[i - 1]) / max_distance
        ok = np.array([visemes[i - 1] in ARPABET_VISEMES[p.phone] for p in phones]) & (dist <= 1.0)
        pair = np.where(ok, dist, np.inf)
        for j in range(1, n + 1):
            options = (cost[i - 1, j - 1] + pair[j - 1], cost[i - 1, j] + 1.0, cost[i, j - 1] + 1.0)
            move[i, j] = int(np.argmin(options))
            cost[i, j] = options[move[i, j]]
    pairs = []
    i, j = m, n
    while i > 0 or j > 0:
        step = move[i, j]
        if step == 0:
            pairs.append((i - 1, j - 1))
            i, j = i - 1, j - 1
        elif step == 1:
            i -= 1
        else:
            j -= 1
    return pairs[::-1]


@dataclass(frozen=True)
class AlignedOffsets:
    """Viseme peaks (or closures) minus the aligned phone onsets they were paired with, seconds."""

    offsets: np.ndarray
    n_spans: int
    n_phones: int

    @property
    def mean(self) -> float:
        return float(self.offsets.mean()) if len(self.offsets) else float("nan")

    @property
    def p95(self) -> float:
        """95th percentile of the offsets' size."""
        return float(np.percentile(np.abs(self.offsets), 95)) if len(self.offsets) else float("nan")


def aligned_onsets(visemes: Sequence[str], starts: np.ndarray, phones: Sequence[AlignedPhone],
                   max_distance: float = 0.15) -> np.ndarray:
    """Per span, the onset of the phone paired with it (:func:`match_phones`); NaN if unpaired."""
    onsets = np.full(len(visemes), np.nan)
    for i, j in match_phones(visemes, np.asarray(starts, dtype=np.float64), phones, max_distance):
        onsets[i] = phones[j].start
    return onsets


def aligned_offsets(visemes: Sequence[str], starts: np.ndarray, times: np.ndarray,
                    phones: Sequence[AlignedPhone], max_distance: float = 0.15) -> AlignedOffsets:
    """``times`` (one per span, NaN to leave out) minus the onset of the phone paired with the span."""
    onsets = aligned_onsets(visemes, starts, phones, max_distance)
    offsets = np.asarray(times, dtype=np.float64) - onsets
    return AlignedOffsets(offsets[np.isfinite(offsets)], len(visemes), len(phones))
