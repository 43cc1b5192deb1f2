"""English forced alignment with pocketsphinx 5.1.1 and its bundled en-us model (no download).

The transcript's words go to ``Decoder.set_align_text``; a first pass aligns the words, a second
(``set_alignment``) the phones inside them; ``get_alignment()`` yields words, each with its phones,
in 10 ms frames. Audio goes in as 16 kHz int16 with one LSB of seeded noise: digital silence gives
the model's log-energy features minus infinity and the search fails.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from mpeg4fa.speech.align.errors import AlignError
from mpeg4fa.speech.align.recording import HOP, Recording, resample

RATE = 16000
"""The bundled acoustic model's sample rate."""
WINDOW = 0.025625
"""The front end's analysis window (410 samples at 16 kHz)."""
OFFSET = WINDOW / 2 - HOP / 2
"""Frame ``t``'s features come from the window starting at ``t`` * 10 ms, centred half a window later; a
boundary between frames ``t-1`` and ``t`` lies between their centres: ``t`` * 10 ms + this."""
STOPS = frozenset({"P", "B", "T", "D", "K", "G", "CH", "JH"})
"""Phones that pocketsphinx starts at the closure (the silence before the burst), espeak-ng at the release."""
_FILLERS = {"SIL", "+NSN+", "+SPN+", "+BREATH+", "+COUGH+", "+UM+", "+NOISE+"}


ESPEAK_ARPABET: dict[str, str] = {
    "p": "P", "b": "B", "m": "M", "f": "F", "v": "V", "T": "TH", "D": "DH", "t": "T", "d": "D", "t#": "T",
    "t2": "T", "t[": "T", "?": "T", "k": "K", "g": "G", "x": "K", "h": "HH", "N": "NG", "tS": "CH", "dZ": "JH",
    "S": "SH", "Z": "ZH", "s": "S", "z": "Z", "n": "N", "n-": "N", "l": "L", "l/": "L", "@L": "AH L", "r": "R",
    "r-": "R", "w": "W", "W": "W", "w#": "W", "j": "Y", "a": "AE", "aa": "AE", "a#": "AH", "A:": "AA", "A@": "AA R",
    "V": "AH", "VR": "AH R", "aI": "AY", "aI2": "AY", "aI3": "AY ER", "aI@": "AY ER", "aU": "AW", "aU@": "AW ER",
    "E": "EH", "e@": "EH R", "eI": "EY", "@": "AH", "@-": "AH", "@2": "AH", "@5": "AH", "3": "ER", "3:": "ER",
    "I": "IH", "I#": "IH", "I2": "IH", "IR": "IH R", "i": "IY", "i:": "IY", "i@": "IH R", "i@3": "IH R", "0": "AA",
    "O:": "AO", "O@": "AO R", "O2": "AO", "OI": "OY", "o@": "AO R", "oU": "OW", "U": "UH", "U@": "UH R", "u:": "UW",
}
"""espeak-ng's English phonemes (``spec/english_visemes.csv``) in the CMU dictionary's ARPAbet: how a word
the dictionary lacks is added, pronounced as espeak-ng says it."""


def arpabet(phonemes: list[str]) -> str | None:
    """espeak-ng phoneme names -> an ARPAbet pronunciation, or None if one has no counterpart."""
    out = []
    for name in phonemes:
        if name == ";":  # palatalisation mark, not a sound
            continue
        if name not in ESPEAK_ARPABET:
            return None
        out.append(ESPEAK_ARPABET[name])
    return " ".join(out) or None


def add_words(pronunciations: dict[str, str]) -> None:
    """Teach the decoder words it lacks (word -> ARPAbet phones), for this process."""
    decoder = shared_decoder()
    items = list(pronunciations.items())
    for n, (word, phones) in enumerate(items):
        try:
            decoder.add_word(word, phones, update=n == len(items) - 1)
        except RuntimeError as exc:
            raise AlignError(f"pocketsphinx cannot take the word {word!r} as {phones} ({exc})",
                             where="pocketsphinx", hint="use the dtw aligner") from None


@dataclass(frozen=True)
class Word:
    """One aligned word: its spelling, start and end (s) and its phones as (ARPAbet, start, end)."""

    word: str
    start: float
    end: float
    phones: tuple[tuple[str, float, float], ...]


@lru_cache(maxsize=1)
def shared_decoder():
    from mpeg4fa.extras import require

    require("align", "pocketsphinx")  # the 'align' extra; without it, auto aligns with DTW (core.choose_method)
    from pocketsphinx import Decoder

    # bestpath off: its lattice rescoring can give the phone pass a path it cannot align
    return Decoder(samprate=RATE, bestpath=False, loglevel="FATAL")


def unknown_words(words: list[str]) -> list[str]:
    """The words the CMU dictionary lacks."""
    decoder = shared_decoder()
    return sorted({w for w in words if decoder.lookup_word(w) is None})


def pcm16k(x: np.ndarray, rate: int, seed: int = 0) -> bytes:
    """Mono float samples ``x`` at ``rate`` as the model takes them: 16 kHz int16 with one LSB of
    seeded noise (see the module docstring)."""
    y = resample(x, rate, RATE) * 32767.0
    y = y + np.random.default_rng(seed).standard_normal(len(y))
    return np.clip(np.rint(y), -32768, 32767).astype("<i2").tobytes()


@lru_cache(maxsize=1)
def free_decoder():
    """A second decoder on the same model, searching a phone loop (the bundled phone trigram LM,
    ``allphone``): the best the model can say of the audio when it need not say the transcript."""
    from mpeg4fa.extras import require

    require("align", "pocketsphinx")
    from pocketsphinx import Decoder, get_model_path

    phone_lm = Path(get_model_path()) / "en-us" / "en-us-phone.lm.bin"
    return Decoder(samprate=RATE, allphone=str(phone_lm), bestpath=False, loglevel="FATAL")


def acoustic_score(decoder) -> tuple[float, int]:
    """The last search's acoustic log-likelihood (pocketsphinx's log units) summed over its segments,
    and the frames of its segments that are words (not silence or a filler)."""
    logmath = decoder.get_logmath()
    segments = list(decoder.seg())
    words = sum(s.end_frame - s.start_frame + 1 for s in segments
                if s.word not in _FILLERS and s.word[:1] not in "<[+")
    return float(sum(logmath.log(s.ascore) for s in segments)), words


def fit_score(pcm: bytes, forced: tuple[float, int]) -> float:
    """The forced alignment's acoustic log-likelihood (``forced``: it and its word frames, from
    :func:`force_align_scored`) minus a free phone-loop decoding's of the same audio (:func:`free_decoder`),
    per frame of the aligned words: near 0 when the transcript is what is said, far below when the
    alignment had to force other words onto the audio (silences score alike in both and would only
    dilute it). Units: pocketsphinx's log scores (base 1.0001, of its scaled senone scores) per 10 ms."""
    decoder = free_decoder()
    decoder.start_utt()
    decoder.process_raw(pcm, full_utt=True)
    decoder.end_utt()
    return (forced[0] - acoustic_score(decoder)[0]) / max(forced[1], 1)


def force_align(pcm: bytes, words: list[str]):
    """pocketsphinx's alignment of ``words`` (lower case, in its dictionary) to ``pcm`` (:func:`pcm16k`):
    words first, then the phones inside them; raises ``RuntimeError`` when it finds no path."""
    return force_align_scored(pcm, words)[0]


def force_align_scored(pcm: bytes, words: list[str]):
    """:func:`force_align`, and the word pass's acoustic score (for :func:`fit_score`)."""
    decoder = shared_decoder()
    decoder.set_align_text(" ".join(words))
    forced = (0.0, 0)
    for second_pass in (False, True):
        if second_pass:
            if decoder.hyp() is None:
                raise RuntimeError("no path through the transcript's words")
            forced = acoustic_score(decoder)
            decoder.set_alignment()
        decoder.start_utt()
        decoder.process_raw(pcm, full_utt=True)
        decoder.end_utt()
    return decoder.get_alignment(), forced


def align_words(rec: Recording, words: list[str], *, fit: bool = True) -> tuple[list[Word], float]:
    """Force-align ``words`` (lower case, in the CMU dictionary) to the recording: the words, and how
    well they fit it (:func:`fit_score`; with ``fit`` off NaN: its free decoding is a quarter of the time of the
    recogniser's words path, which needs no fit)."""
    pcm = pcm16k(rec.floats(), rec.rate)
    try:
        alignment, forced = force_align_scored(pcm, words)
    except RuntimeError as exc:
        raise AlignError(f"the transcript does not fit the recording: pocketsphinx found no path through it ({exc})",
                         where=rec.name, hint="check the transcript is what the recording says") from None
    out = []
    for word in alignment:
        if word.name in _FILLERS or word.name.startswith("<"):
            continue
        spelling = re.sub(r"\(\d+\)$", "", word.name)
        phones = tuple((p.name, p.start * HOP + OFFSET, (p.start + p.duration) * HOP + OFFSET)
                       for p in word if p.name not in _FILLERS)
        out.append(Word(spelling, word.start * HOP + OFFSET, (word.start + word.duration) * HOP + OFFSET, phones))
    if [w.word for w in out] != words:
        raise AlignError("the transcript does not fit the recording: pocketsphinx aligned "
                         f"{len(out)} of its {len(words)} words", where=rec.name,
                         hint="check the transcript is what the recording says")
    return out, fit_score(pcm, forced) if fit else float("nan")
