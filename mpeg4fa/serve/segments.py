"""One sentence made ready to send: spoken and encoded as an FBA stream (its fba_object), and its audio.

The face goes out as the bitstream itself (the page decodes it with fba.js, as the standard
intends: a few hundred bits per second); the segment also keeps the media times of the decoded
stream's frames (its timestamps, its skips), which the server counts and a test compares.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.fba import decode, encode
from mpeg4fa.serve.sentences import Sentence
from mpeg4fa.speech.encoder import encode_text
from mpeg4fa.speech.tts.base import Engine


@dataclass(frozen=True)
class Segment:
    index: int
    text: str          # what is spoken
    start: float       # media time of the segment's first sample, s
    rate: int          # audio sample rate, Hz
    audio: np.ndarray  # int16 mono
    fba: bytes         # the segment's fba_object
    times: np.ndarray  # (n,) media times of the decoded frames

    @property
    def duration(self) -> float:
        return len(self.audio) / self.rate

    @property
    def end(self) -> float:
        return self.start + self.duration


def make_segment(sentence: Sentence, start: float, *, engine: Engine, lang: str = "auto",
                 voice: str | None = None, rate: int | None = None, fps: float = 25.0) -> Segment:
    """Speak one sentence and encode it as one fba_object starting at media time ``start``."""
    encoded = encode_text(sentence.text, engine=engine, lang=lang, voice=voice, rate=rate, fps=fps,
                          name=f"sentence {sentence.index + 1}")
    data = encode(encoded.stream, encoded.coding())
    stream = decode(data)  # the frames a receiver gets (skips folded in): their times
    speech = encoded.speech
    return Segment(index=sentence.index, text=sentence.plain, start=start, rate=speech.rate,
                   audio=np.ascontiguousarray(speech.samples, dtype="<i2"), fba=data,
                   times=start + np.asarray(stream.timestamps, np.float64))


def chunks(segment: Segment, chunk: float) -> list[tuple[float, np.ndarray]]:
    """The segment's audio as (media time, int16 samples), ``chunk`` s each, in time order (its face
    goes out whole, as one FBA message, before them)."""
    step = max(1, int(round(chunk * segment.rate)))
    return [(segment.start + a / segment.rate, segment.audio[a:a + step]) for a in range(0, len(segment.audio), step)]
