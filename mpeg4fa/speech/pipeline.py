"""Text to stream as one line of passes, chunk by chunk: parse -> speak -> phones -> frames -> bits.

Each pass is one module, visited once per chunk, and hands the next what it made:

1. parse (:mod:`.chunks`): the tagged text, in chunks of whole sentences with their tags;
2. speak (:func:`.utterance.speak`): a chunk's audio, phoneme events and visemes, tags timed;
3. phones (:func:`.encoder.phones`): stops moved to their closures; then the chunk is placed on
   the text's clock (its start is where the chunks before it ended);
4. frames (:class:`.frames.FrameMaker`): visemes, expressions and idle motion sampled at the
   frame rate, running on across chunks; the frames that can no longer change come out;
5. bits (:class:`.encoder.StreamBuilder`, :class:`.bits.FbaBlocks`): FAP streams, coded and
   written as they fill.

:func:`stream_text` writes the stream, the audio (:class:`mpeg4fa.wav.PcmWriter`) and the timings
(:class:`TimingsWriter`) as the chunks come, so memory is that of a chunk and a block whatever the
text's length; :func:`encode_text_to` does it to files that appear whole or not at all.
:func:`encoded_text` keeps everything in memory (:func:`.encoder.encode_text`: short texts).
"""
from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mpeg4fa.speech.chunks import CHUNK_CHARS, parse_pieces, sentence_chunks
from mpeg4fa.speech.errors import MarkupError, TTSError
from mpeg4fa.speech.frames import FrameBlock, FrameMaker
from mpeg4fa.speech.ipa import phoneme_fallbacks
from mpeg4fa.speech.markup import Markup
from mpeg4fa.speech.timeline import ExpressionCue
from mpeg4fa.speech.tts.base import Engine, Speech
from mpeg4fa.speech.utterance import Utterance, speak

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class Chunk:
    """One chunk through the passes: its markup, its utterance on the text's clock (times from the
    text's start; the speech is the chunk's own audio), and the frames that became final."""

    markup: Markup
    utterance: Utterance
    offset: float
    frames: FrameBlock | None


@dataclass(frozen=True)
class Spoken:
    """What :func:`stream_text` wrote: seconds of speech, frames, stream bytes, chunks, engine, wall time."""

    seconds: float
    frames: int
    bytes: int
    chunks: int
    engine: str
    wall: float

    @property
    def speed(self) -> float:
        """Seconds of speech per second of wall time."""
        return self.seconds / self.wall if self.wall > 0 else float("inf")


class Passes:
    """The line of passes over one text (see the module docstring); iterate for the :class:`Chunk` s,
    then :meth:`finish` for the last frames. ``max_seconds`` refuses speech longer than that, at the
    place in the text where it runs over."""

    def __init__(self, text: str, engine: Engine, *, lang: str = "auto", voice: str | None = None,
                 rate: int | None = None, fps: float = 25.0, idle: bool = False, seed: int = 0,
                 fields: bool = True, name: str = "<text>", chunk_chars: int = CHUNK_CHARS,
                 progress: Progress | None = None, max_seconds: float | None = None,
                 **markup_options) -> None:
        from mpeg4fa.speech.encoder import closure_hold

        self.text, self.engine, self.name = text, engine, name
        self.speak_options = {"lang": lang, "voice": voice, "rate": rate}
        self.markup_options = markup_options
        self.frames = FrameMaker(fps, idle=idle, seed=seed, closure_hold=closure_hold(fps), fields=fields)
        self.chunk_chars, self.progress, self.max_seconds = chunk_chars, progress, max_seconds
        self.offset = 0.0
        self.samples = 0
        self.rate: int | None = None
        self.chunks = 0
        self.place = (name, 1, 1)

    def __iter__(self) -> Iterator[Chunk]:
        total = max(len(self.text), 1)
        if self.progress is not None:
            self.progress(0, total)
        with phoneme_fallbacks(self.name):  # one warning for the whole text, however many chunks it is spoken in
            yield from self._chunks(total)
        if not self.chunks:
            raise MarkupError("there is nothing to say", 1, 1, hint="give some text", source=self.name)

    def _chunks(self, total: int) -> Iterator[Chunk]:
        from mpeg4fa.speech.encoder import phones

        done = 0
        for piece in parse_pieces(self.text, name=self.name, **self.markup_options):
            for markup in sentence_chunks(piece, self.chunk_chars):
                if not markup.text.strip():
                    continue
                line, column = markup.place(0)
                self.place = (self.name, line, column)
                utterance = phones(speak(markup, self.engine, **self.speak_options))
                speech = utterance.speech
                if self.rate is None:
                    self.rate = speech.rate
                elif speech.rate != self.rate:
                    raise TTSError(f"chunks came back at {speech.rate} and {self.rate} Hz", where=self.engine.name)
                placed = _shifted(utterance, self.offset)
                self.samples += len(speech.samples)
                until = self.offset + speech.duration
                if self.max_seconds is not None and until > self.max_seconds:
                    raise MarkupError(f"the speech runs past {self.max_seconds:g} s here", line, column,
                                      "say renders at most that much; encode the text to a stream with "
                                      "'mpeg4fa encode' (no limit but the stream's 24 h), or split it", self.name)
                block = self.frames.add(placed.spans(), placed.cues, until)
                yield Chunk(markup, placed, self.offset, block)
                self.offset = until
                self.chunks += 1
                done = min(done + len(markup.text), total - 1)
                if self.progress is not None:
                    self.progress(done, total)

    @property
    def duration(self) -> float:
        """Seconds of speech so far: all the samples at their rate (as one joined track would say)."""
        return self.samples / self.rate if self.rate else 0.0

    def finish(self) -> FrameBlock:
        block = self.frames.finish(self.duration)
        if self.progress is not None:
            total = max(len(self.text), 1)
            self.progress(total, total)
        return block


def _shifted(utterance: Utterance, offset: float) -> Utterance:
    """The utterance's timings and cues on the text's clock (the chunk starts ``offset`` seconds in)."""
    if offset == 0.0:
        return utterance
    timings = tuple(t.shifted(offset) for t in utterance.timings)
    cues = tuple(ExpressionCue(c.expression, c.intensity, c.seconds, c.start + offset) for c in utterance.cues)
    return Utterance(utterance.speech, timings, cues, utterance.markup)


def joined_speech(parts: list[tuple[Speech, float]], engine: str) -> Speech:
    """Chunks' speech (each with its offset) as one track, events on the text's clock."""
    first = parts[0][0]
    events = tuple(e.shifted(offset) for speech, offset in parts for e in speech.events)
    voices = "+".join(dict.fromkeys(s.voice for s, _ in parts))
    return Speech(np.concatenate([s.samples for s, _ in parts]), first.rate, events, engine, voices)


class TimingsWriter:
    """The timed visemes as a JSON list written as they come, the same text ``json.dumps(..., indent=1)``
    gives for the whole list (:func:`mpeg4fa.say.write_timings`)."""

    def __init__(self, handle) -> None:
        self.handle = handle
        self.count = 0

    def add(self, timings) -> None:
        for timing in timings:
            item = json.dumps(timing.as_dict(), ensure_ascii=False, indent=1).replace("\n", "\n ")
            self.handle.write(("[\n " if not self.count else ",\n ") + item)
            self.count += 1

    def close(self) -> None:
        self.handle.write("\n]\n" if self.count else "[]\n")


def stream_text(text: str, out, *, audio=None, timings=None, engine: Engine | str = "espeak", lang: str = "auto",
                voice: str | None = None, rate: int | None = None, fps: float = 25.0, level: str = "high",
                idle: bool = False, seed: int = 0, name: str = "<text>", fold: bool = True, compact: bool = True,
                options=None, progress: Progress | None = None, chunk_chars: int = CHUNK_CHARS,
                **markup_options) -> Spoken:
    """Speak tagged ``text`` and write, chunk by chunk, its FBA stream to the binary file ``out``, its
    speech as WAV to the binary file ``audio`` and its timed visemes as JSON to the text file
    ``timings`` (each optional but ``out``). ``options`` (:class:`~mpeg4fa.fba.EncodeOptions`) code
    the stream, :data:`~.encoder.TEXT_CODING` by default; ``progress(done, total)`` counts characters.
    The stream decodes to what :func:`~.encoder.encode_text` of the same chunks would (see
    :mod:`.bits`)."""
    from mpeg4fa.fba import EncodeOptions
    from mpeg4fa.speech.bits import FbaBlocks
    from mpeg4fa.speech.encoder import LEVELS, TEXT_CODING, StreamBuilder, make_engine
    from mpeg4fa.wav import PcmWriter

    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    started = time.perf_counter()
    speaker = make_engine(engine) if isinstance(engine, str) else engine
    passes = Passes(text, speaker, lang=lang, voice=voice, rate=rate, fps=fps, idle=idle, seed=seed,
                    fields=level != "low", name=name, chunk_chars=chunk_chars, progress=progress, **markup_options)
    builder = StreamBuilder(level, fps, fold=fold, compact=compact)
    options = options if options is not None else EncodeOptions(**TEXT_CODING)
    bits = FbaBlocks(out, builder.build, options, fps, place=lambda: passes.place)
    wav = None
    listed = TimingsWriter(timings) if timings is not None else None
    engine_name = speaker.name
    try:  # the passes warn once for phonemes shown by a guess, over the whole text (Passes.__iter__)
        for chunk in passes:
            speech = chunk.utterance.speech
            if audio is not None:
                if wav is None:
                    wav = PcmWriter(audio, speech.rate, name=getattr(audio, "name", "<wav>"))
                wav.write(speech.samples)
            if listed is not None:
                listed.add(chunk.utterance.timings)
            bits.add(chunk.frames)
            engine_name = speech.engine
        bits.add(passes.finish())
        bits.finish()
    except BaseException:
        if wav is not None:
            wav.abandon()
        raise
    if wav is not None:
        wav.close()
    if listed is not None:
        listed.close()
    return Spoken(passes.duration, bits.frames, bits.bytes, passes.chunks, engine_name,
                  time.perf_counter() - started)


def stream_utterance(utterance: Utterance, out, *, timings=None, fps: float = 25.0, level: str = "high",
                     idle: bool = False, seed: int = 0, fold: bool = True, compact: bool = True, options=None,
                     name: str = "<events>") -> Spoken:
    """:func:`~.encoder.encode_utterance` of a timed utterance (viseme events, an aligned recording) written to
    the binary file ``out`` as it is coded, block by block (:class:`~.bits.FbaBlocks`), and its timed visemes
    to the text file ``timings``: the same passes (phones -> frames -> bits), the memory of the frames and a
    block rather than of the whole coded stream (30 min of viseme events: 400 MB in memory, about half
    streamed). A stream of one block has the bytes ``encode(encode_utterance(...).stream)`` gives."""
    from mpeg4fa.fba import EncodeOptions
    from mpeg4fa.speech.bits import FbaBlocks
    from mpeg4fa.speech.encoder import LEVELS, TEXT_CODING, StreamBuilder, closure_hold, phones

    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    started = time.perf_counter()
    utterance = phones(utterance)
    maker = FrameMaker(fps, idle=idle, seed=seed, closure_hold=closure_hold(fps), fields=level != "low")
    builder = StreamBuilder(level, fps, fold=fold, compact=compact)
    bits = FbaBlocks(out, builder.build, options if options is not None else EncodeOptions(**TEXT_CODING), fps,
                     place=lambda: (name, 1, 1))
    duration = utterance.speech.duration
    bits.add(maker.add(utterance.spans(), utterance.cues, duration))
    bits.add(maker.finish(duration))
    bits.finish()
    if timings is not None:
        listed = TimingsWriter(timings)
        listed.add(utterance.timings)
        listed.close()
    return Spoken(duration, bits.frames, bits.bytes, 1, utterance.speech.engine, time.perf_counter() - started)


def encode_text_to(text: str, out: str | os.PathLike, *, audio: str | os.PathLike | None = None,
                   timings: str | os.PathLike | None = None, **kwargs) -> Spoken:
    """:func:`stream_text` to files: the stream ``out``, and ``audio`` (WAV) and ``timings`` (JSON) when
    given; all appear whole once the text is spoken, or none (:func:`mpeg4fa.atomic.atomic_outputs`)."""
    from mpeg4fa.atomic import atomic_outputs

    with atomic_outputs(out, audio, timings) as (out_path, audio_path, timings_path):
        with open(out_path, "wb") as out_file, _opened(audio_path, "wb") as audio_file, \
                _opened(timings_path, "w") as timings_file:
            return stream_text(text, out_file, audio=audio_file, timings=timings_file, **kwargs)


class _opened:
    """``open(path, mode)``, or nothing for no path."""

    def __init__(self, path: Path | None, mode: str) -> None:
        self.path, self.mode, self.file = path, mode, None

    def __enter__(self):
        if self.path is not None:
            self.file = open(self.path, self.mode, **({"encoding": "utf-8"} if "b" not in self.mode else {}))
        return self.file

    def __exit__(self, *exc) -> None:
        if self.file is not None:
            self.file.close()


def encoded_text(text: str, engine: Engine, *, fps: float = 25.0, level: str = "high", idle: bool = False,
                 seed: int = 0, name: str = "<text>", fold: bool = True, compact: bool = True,
                 lang: str = "auto", voice: str | None = None, rate: int | None = None,
                 chunk_chars: int = CHUNK_CHARS, max_seconds: float | None = None,
                 progress: Progress | None = None, **markup_options):
    """The passes over ``text`` kept in memory: an :class:`~.encoder.Encoded` of one stream of all the
    frames, its utterance the chunks' joined (a text of one chunk: exactly the utterance spoken)."""
    from mpeg4fa.speech.encoder import Encoded, StreamBuilder, join_blocks

    passes = Passes(text, engine, lang=lang, voice=voice, rate=rate, fps=fps, idle=idle, seed=seed,
                    fields=level != "low", name=name, chunk_chars=chunk_chars, progress=progress,
                    max_seconds=max_seconds, **markup_options)
    chunks = list(passes)  # the passes warn once for phonemes shown by a guess (Passes.__iter__)
    blocks = [c.frames for c in chunks if c.frames is not None] + [passes.finish()]
    block = join_blocks(blocks)
    stream = StreamBuilder(level, fps, fold=fold, compact=compact).build(block)
    if len(chunks) == 1:
        utterance = chunks[0].utterance
    else:
        first = chunks[0].utterance
        speech = joined_speech([(c.utterance.speech, c.offset) for c in chunks], first.speech.engine)
        utterance = Utterance(speech, tuple(t for c in chunks for t in c.utterance.timings),
                              tuple(q for c in chunks for q in c.utterance.cues), _joined_markup(chunks, name))
    return Encoded(stream, utterance, block.values, level)


def _joined_markup(chunks: list[Chunk], name: str) -> Markup:
    """The chunks' markup as one, a space between chunks (what an utterance of the whole text carries)."""
    text, tags, places, at = [], [], [], 0
    for chunk in chunks:
        m = chunk.markup
        tags += [replace(tag, offset=tag.offset + at) for tag in m.tags]
        text.append(m.text)
        places += list(m.places) + [m.place(len(m.text) - 1)] if m.text else list(m.places)
        at += len(m.text) + 1
    return Markup(" ".join(text), tuple(tags), name, tuple(places[:at - 1]))
