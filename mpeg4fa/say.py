"""Say it: tagged text -> speech and FAPs -> the FBA stream -> decoded again -> the face saying it (MP4/PNG).

Why a module of its own at the top of the package: ``say`` runs both branches of the data
flow, the encoder (:mod:`mpeg4fa.speech`, :mod:`mpeg4fa.fba`) and the decoder's playback
(:mod:`mpeg4fa.render`), so it lives above them and neither layer imports the other. The
face plays what a receiver would decode, not the encoder's own values.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from mpeg4fa.atomic import atomic_output

if TYPE_CHECKING:  # pragma: no cover
    from mpeg4fa.face import FaceModel
    from mpeg4fa.fba import FapStream
    from mpeg4fa.render.player import PlayResult
    from mpeg4fa.speech.encoder import Encoded

KEPT = {"stream": ".fba", "audio": ".wav", "timings": ".timings.json"}
"""What ``keep=True`` writes beside the output: OUT.fba, OUT.wav, OUT.timings.json."""


@dataclass(frozen=True)
class Said:
    """What :func:`say` made: the encoder's output, the stream's bytes, what a receiver decodes, the render."""

    encoded: "Encoded"
    data: bytes
    stream: "FapStream"
    result: "PlayResult"
    kept: dict[str, Path]


def kept_paths(out: str | os.PathLike) -> dict[str, Path]:
    """The files ``keep=True`` writes for output ``out`` (so a caller can check them before starting)."""
    path = Path(out)
    base = (path if path.name else path.resolve()).with_suffix("")
    return {what: base.with_name(base.name + suffix) for what, suffix in KEPT.items()}


MAX_SAY_SECONDS = 20 * 60
"""Most speech :func:`say` renders: 20 minutes. It holds the speech, the frames and the render's
audio in memory, and a render runs near real time, so longer text is refused where it runs over
(before any rendering), with the way out: ``mpeg4fa encode`` streams text of any length."""


def write_timings(encoded: "Encoded", path: str | os.PathLike) -> None:
    """The timed visemes as JSON: ``[{"phoneme", "viseme", "start", "end"}, ...]``, seconds in the audio."""
    from mpeg4fa.speech.pipeline import TimingsWriter

    with atomic_output(path) as partial, open(partial, "w", encoding="utf-8") as handle:
        listed = TimingsWriter(handle)
        listed.add(encoded.utterance.timings)
        listed.close()


def say(text: str, out: str | os.PathLike, *, engine: str = "espeak", lang: str = "auto", voice: str | None = None,
        rate: int | None = None, fps: float = 25.0, level: str = "low", idle: bool = False, width: int = 512,
        height: int = 512, samples: int = 4, keep: bool = False, face: "FaceModel | None" = None,
        name: str = "<text>", progress: Callable[[int, int], None] | None = None, lenient: bool = False,
        texture=None) -> Said:
    """Speak tagged ``text`` and render ``face`` (the generic head by default) saying it to ``out``.

    ``out``: .mp4/.mov/.m4v, else a folder of PNG frames (see :func:`mpeg4fa.render.play`).
    ``lenient`` speaks malformed tags as text, with one warning (:func:`mpeg4fa.speech.markup.parse_markup`).
    ``texture``: the skin's UV texture image (e.g. baked from the FDP of a photo: ``mpeg4fa say --photo``).
    Speech longer than :data:`MAX_SAY_SECONDS` is refused (a :class:`~mpeg4fa.speech.MarkupError` at the
    place it runs over) before anything is rendered.
    ``keep`` also writes :func:`kept_paths` (the stream, the speech as WAV, the timings), after
    the render succeeded. Every file appears whole or not at all (:mod:`mpeg4fa.atomic`).
    Errors are the layers' own (:class:`~mpeg4fa.speech.MarkupError`, ``TTSError``, ``RenderError``...).
    """
    from mpeg4fa.speech.encoder import encode_text

    encoded = encode_text(text, engine=engine, lang=lang, voice=voice, rate=rate, fps=fps, level=level, idle=idle,
                          name=name, lenient=lenient, max_seconds=MAX_SAY_SECONDS)
    return say_encoded(encoded, out, width=width, height=height, samples=samples, keep=keep, face=face,
                       progress=progress, texture=texture)


def say_encoded(encoded, out: str | os.PathLike, *, width: int = 512, height: int = 512, samples: int = 4,
                keep: bool = False, face: "FaceModel | None" = None,
                progress: Callable[[int, int], None] | None = None, texture=None) -> Said:
    """:func:`say` from an encoded stream on (spoken text, or a recording with its aligned transcript):
    coded, decoded again (the face plays what a receiver would decode), rendered with the speech, and
    the files of ``keep`` written once the render succeeded."""
    import numpy as np

    from mpeg4fa.face import FaceModel
    from mpeg4fa.fba import decode, encode
    from mpeg4fa.render import Audio, play

    data = encode(encoded.stream, encoded.coding())
    stream = decode(data)
    speech = encoded.speech
    audio = Audio((speech.samples.astype(np.float32) / 32768.0)[:, None], speech.rate)
    result = play(stream, out, face=face if face is not None else FaceModel.default(), audio=audio, width=width,
                  height=height, samples=samples, progress=progress,
                  **({"texture": texture} if texture is not None else {}))
    kept: dict[str, Path] = {}
    if keep:
        kept = kept_paths(out)
        with atomic_output(kept["stream"]) as partial:
            Path(partial).write_bytes(data)
        speech.write_wav(kept["audio"])
        write_timings(encoded, kept["timings"])
    return Said(encoded, data, stream, result, kept)
