"""What every speech engine hands back: audio plus timed events, as plain frozen data.

The encoder only needs the audio and *when* each phoneme, word and mark happens in it, so an
engine is reduced to one call (``Engine.synthesize``) returning a ``Speech``. Keeping the result
free of engine objects lets it be pickled, cached and compared in tests.
"""
from __future__ import annotations

import bisect
import re
from dataclasses import dataclass
from os import PathLike
from typing import Literal, Protocol, Sequence, runtime_checkable

import numpy as np

from mpeg4fa.wav import write_pcm16

EventKind = Literal["phoneme", "word", "sentence", "mark", "end"]
EVENT_KINDS: tuple[str, ...] = ("phoneme", "word", "sentence", "mark", "end")


@dataclass(frozen=True)
class Event:
    """One timed happening in the audio; times are seconds from the first sample.

    ``end`` closes the interval (phonemes, words, sentences: the next one of the same kind, or
    the end of the audio); point events (marks, end of message) have ``end == start``.
    ``position`` is the 0-based character index in the synthesized text, or -1 when unknown.
    """

    kind: EventKind
    start: float
    end: float
    text: str
    position: int = -1

    def __post_init__(self) -> None:
        if self.kind not in EVENT_KINDS:
            raise ValueError(f"unknown event kind {self.kind!r}; expected one of {EVENT_KINDS}")
        if self.end < self.start:
            raise ValueError(f"event ends before it starts: {self.start} > {self.end}")

    def shifted(self, seconds: float) -> "Event":
        """The same event ``seconds`` later (a part's event on the whole's clock)."""
        return Event(self.kind, self.start + seconds, self.end + seconds, self.text, self.position)

    @property
    def duration(self) -> float:
        """Length of the interval in seconds (0 for point events)."""
        return self.end - self.start


@dataclass(frozen=True)
class Speech:
    """Synthesized mono audio and its events (sorted by start), tagged with engine and voice."""

    samples: np.ndarray
    rate: int
    events: tuple[Event, ...]
    engine: str
    voice: str

    def __post_init__(self) -> None:
        samples = np.asarray(self.samples)
        if samples.dtype != np.int16 or samples.ndim != 1:
            raise ValueError(f"samples must be int16 mono (n,), got {samples.dtype} {samples.shape}")
        if self.rate <= 0:
            raise ValueError(f"sample rate must be positive, got {self.rate}")
        object.__setattr__(self, "samples", samples)
        object.__setattr__(self, "events", tuple(self.events))

    @property
    def duration(self) -> float:
        """Audio length in seconds (what the timeline must cover)."""
        return len(self.samples) / self.rate

    def write_wav(self, path: str | PathLike[str]) -> None:
        """Write a 16-bit mono PCM WAV file (the audio track to mux with the animation)."""
        write_pcm16(path, self.samples, self.rate)

    def _of(self, kind: str) -> tuple[Event, ...]:
        return tuple(e for e in self.events if e.kind == kind)

    def phonemes(self) -> tuple[Event, ...]:
        """Phoneme events (pauses included: their text starts with ``_``)."""
        return self._of("phoneme")

    def words(self) -> tuple[Event, ...]:
        """Word events; ``text`` is the word as written in the input."""
        return self._of("word")

    def marks(self) -> tuple[Event, ...]:
        """Mark events; ``text`` is the mark's name."""
        return self._of("mark")


@runtime_checkable
class Engine(Protocol):
    """A text-to-speech engine that reports timing, so visemes can follow the audio."""

    name: str

    def synthesize(
        self,
        text: str,
        *,
        voice: str | None = None,
        rate: int | None = None,
        marks: Sequence[tuple[int, str]] = (),
    ) -> Speech:
        """Speak ``text``; ``marks`` are (character offset in ``text``, name) pairs whose times
        come back as mark events (where expression tags sit inside the text)."""
        ...


_WORD = re.compile(r"[^\W_]+(?:'[^\W_]+)*")


def word_tokens(text: str) -> list[tuple[int, int, str]]:
    """(start, end, word) for each run of letters and digits (an inner apostrophe kept: don't)."""
    return [(m.start(), m.end(), m.group()) for m in _WORD.finditer(text)]


def snap_to_tokens(positions: Sequence[int], tokens: Sequence[tuple[int, int, str]]) -> list[int]:
    """Index of the token each engine position falls in, or of the next token (-1: past the end).

    Engines report a word's character position loosely (espeak one character late after a
    sentence end, or on the space before it); snapping makes positions comparable with the text.
    """
    starts = [t[0] for t in tokens]
    out = []
    for p in positions:
        k = bisect.bisect_right(starts, p) - 1
        if k < 0 or p >= tokens[k][1]:
            k += 1
        out.append(k if k < len(tokens) else -1)
    return out
