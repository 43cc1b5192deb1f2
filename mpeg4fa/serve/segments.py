"""One sentence made ready to send: spoken, encoded as an FBA stream, decoded back, weighed in ARKit units.

The frames sent are the *decoded* stream's (its timestamps, its skips), and the weights are
computed from what a decoder shows (:func:`mpeg4fa.decoded.resolve` of the decoded frames,
then the ARKit deformer's unit weights through :mod:`mpeg4fa.export.arkit_units`, the
mapping the exported GLB's morph targets use), so a client that decodes the FBA bytes itself and
one that takes the weights see the same face.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from mpeg4fa.decoded import ClampWarning, resolve
from mpeg4fa.fba import decode, encode
from mpeg4fa.serve.sentences import Sentence
from mpeg4fa.speech.encoder import encode_text
from mpeg4fa.speech.tts.base import Engine

WEIGHT_DECIMALS = 3


@dataclass(frozen=True)
class Segment:
    index: int
    text: str          # what is spoken
    start: float       # media time of the segment's first sample, s
    rate: int          # audio sample rate, Hz
    audio: np.ndarray  # int16 mono
    fba: bytes         # the segment's fba_object
    times: np.ndarray  # (n,) media times of the decoded frames
    weights: np.ndarray  # (n, U) ARKit unit weights, 0..1 (U = 0 for a head without units)

    @property
    def duration(self) -> float:
        return len(self.audio) / self.rate

    @property
    def end(self) -> float:
        return self.start + self.duration


def make_segment(sentence: Sentence, start: float, *, engine: Engine, units, lang: str = "auto",
                 voice: str | None = None, rate: int | None = None, fps: float = 25.0) -> Segment:
    """Speak one sentence and encode it; ``units``: an :class:`~mpeg4fa.export.arkit_units.ArkitUnits` or None."""
    encoded = encode_text(sentence.text, engine=engine, lang=lang, voice=voice, rate=rate, fps=fps,
                          name=f"sentence {sentence.index + 1}")
    data = encode(encoded.stream, encoded.coding())
    stream = decode(data)
    with warnings.catch_warnings():  # a clamp is the decoder's business; the weights are clipped anyway
        warnings.simplefilter("ignore", ClampWarning)
        values = resolve(stream)
    weights = (np.round(units.weights(values), WEIGHT_DECIMALS) if units is not None
               else np.zeros((len(stream), 0)))
    speech = encoded.speech
    return Segment(index=sentence.index, text=sentence.plain, start=start, rate=speech.rate,
                   audio=np.ascontiguousarray(speech.samples, dtype="<i2"), fba=data,
                   times=start + np.asarray(stream.timestamps, np.float64), weights=weights)


def chunks(segment: Segment, chunk: float) -> list[tuple[float, str, object]]:
    """The segment's frames and audio as (media time, kind, payload) in time order, ``chunk`` s each:
    ``("frames", (times, weights))`` and ``("audio", int16 samples)``."""
    items: list[tuple[float, int, str, object]] = []
    if len(segment.times):
        edges = np.floor((segment.times - segment.start) / chunk + 1e-9).astype(np.int64)
        cut = np.flatnonzero(np.diff(edges)) + 1
        for a, b in zip(np.r_[0, cut], np.r_[cut, len(edges)]):
            items.append((float(segment.times[a]), 0, "frames", (segment.times[a:b], segment.weights[a:b])))
    step = max(1, int(round(chunk * segment.rate)))
    for a in range(0, len(segment.audio), step):
        items.append((segment.start + a / segment.rate, 1, "audio", segment.audio[a:a + step]))
    items.sort(key=lambda item: (item[0], item[1]))  # frames before the audio of the same instant
    return [(t, kind, payload) for t, _, kind, payload in items]
