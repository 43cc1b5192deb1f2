"""A silent engine: word times estimated from the spelling, no audio synthesized.

For batch work and tests where no speech is needed (or none can be made): each word lasts
its units' weights times :data:`~mpeg4fa.speech.graphemes.UNIT` at the speech rate, and
punctuation adds the pauses espeak-ng makes (measured on espeak-ng 1.52 at 175 words per
minute). The audio is silence of the estimated length, so the timeline and the player
have a duration to cover. Pinyin (``ni3 hao3``) is read syllable by syllable.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from mpeg4fa.speech.errors import TTSError
from mpeg4fa.speech.graphemes import REFERENCE_RATE, SYLLABLE_UNIT, english_units, pinyin_units, seconds_per_unit
from mpeg4fa.speech.tts.base import Event, Speech, word_tokens

SAMPLE_RATE = 22050
_PAUSES = {",": 0.16, "，": 0.16, "、": 0.16, ";": 0.23, "；": 0.23, ":": 0.23, "：": 0.23,
           ".": 0.30, "。": 0.30, "!": 0.30, "！": 0.30, "?": 0.30, "？": 0.30}
_END_PAUSE = 0.30  # espeak's pause at the end of the text


def _is_pinyin(voice: str) -> bool:
    return "pinyin" in voice.lower()


class EstimateEngine:
    """Word events from a duration model; silent audio. Voices only choose English or pinyin reading."""

    name = "estimate"

    def __init__(self, voice: str = "en-us", rate: int = REFERENCE_RATE) -> None:
        self.voice = voice
        self.rate = rate

    def synthesize(self, text: str, *, voice: str | None = None, rate: int | None = None,
                   marks: Sequence[tuple[int, str]] = ()) -> Speech:
        """Estimated word events for ``text`` (marks are left to the caller: they take the next word's start)."""
        voice = voice or self.voice
        wpm = rate or self.rate
        if wpm <= 0:
            raise TTSError(f"rate {wpm} words per minute must be positive", where=self.name)
        tokens = word_tokens(text)
        if not tokens:
            raise TTSError("nothing to say: the text has no words", where=self.name, hint="pass some words")
        pinyin = _is_pinyin(voice)
        scale = REFERENCE_RATE / float(wpm)
        english, syllable = seconds_per_unit(wpm), seconds_per_unit(wpm, SYLLABLE_UNIT)
        events: list[Event] = []
        t = 0.0
        for k, (start, end, word) in enumerate(tokens):
            units = pinyin_units(word) if pinyin else []
            length = sum(u.weight for u in units) * syllable if units else \
                sum(u.weight for u in english_units(word)) * english
            length = max(length, 0.05 * scale)  # a word the table cannot read still takes a moment
            events.append(Event("word", t, t + length, word, start))
            if k + 1 < len(tokens):
                between = text[end:tokens[k + 1][0]]
                t += length + scale * max((_PAUSES.get(ch, 0.0) for ch in between), default=0.0)
        duration = events[-1].end + _END_PAUSE * scale
        samples = np.zeros(int(round(duration * SAMPLE_RATE)), np.int16)
        events.append(Event("end", duration, duration, ""))
        return Speech(samples, SAMPLE_RATE, tuple(events), self.name, voice)
