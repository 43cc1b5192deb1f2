"""A recording of any length (a WAV file, other audio, or raw PCM from a pipe) -> an FBA stream, block by
block, with the memory of a block.

The audio is read in blocks of about :data:`BLOCK_SECONDS`, each cut at the quietest 10 ms of its last
:data:`CUT_SECONDS` (between words, not inside one), and a last block that would be heard alone in two at the
pause nearest its middle, where it has one (so that a short clip has both cores too); each block is heard on
its own (:func:`.core.listen`) and goes through the encoder's passes on the recording's clock: phones (stops
from their closures) -> frames (:class:`~mpeg4fa.speech.frames.FrameMaker`, running on across blocks) -> bits
(:class:`~mpeg4fa.speech.bits.FbaBlocks`). The timings are written as they come.
"""
from __future__ import annotations

import contextlib
import json
import os
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mpeg4fa.speech.align.errors import AlignError
from mpeg4fa.speech.align.recording import HOP, Recording, frame_levels, speech_frames
from mpeg4fa.speech.listen.core import (Listened, check_language, choose_recognizer, expression_cues, listen,
                                        phone_loop, settled)
from mpeg4fa.speech.listen.voice import voice_activity
from mpeg4fa.speech.utterance import viseme_spans
from mpeg4fa.speech.visemes import PAUSE

BLOCK_SECONDS = 30.0
"""Audio heard at a time."""
CUT_SECONDS = 3.0
"""A block ends at the quietest 10 ms of its last this many seconds."""
SPLIT_SECONDS = 4.0
"""A last block heard alone is cut in two from this length on (:func:`blocks`)."""
PAUSE_SECONDS = 0.08
"""The shortest pause that cut is put in (:func:`_middle_pause`): between words, not a stop's closure."""
RAW_RATE = 16000
"""Sample rate of raw PCM (``encode --speech -``) unless told otherwise."""
RAW_FORMAT = "signed 16-bit little-endian mono (s16le)"

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class Source:
    """Where the audio comes from: a name, its rate, its length in seconds when known (else None), and
    an iterator of mono int16 pieces at that rate."""

    name: str
    rate: int
    seconds: float | None
    pieces: Iterator[np.ndarray]


def wav_source(path: str | os.PathLike) -> Source:
    """A WAV file read piece by piece (any length), or other audio (MP3, FLAC...) read whole by
    :func:`~mpeg4fa.speech.align.read_recording`; errors are :class:`AlignError` at their place."""
    from mpeg4fa.speech.align.recording import read_recording
    from mpeg4fa.wavread import WavError, _mono_int16, wav_info

    path = Path(path)
    if not path.is_file():
        read_recording(path)  # the located "no such recording" / "not a file"
    try:
        info = wav_info(path)
    except WavError:
        rec = read_recording(path)  # other audio through PyAV, or the WAV error at its byte
        return Source(str(path), rec.rate, rec.duration, iter([rec.samples]))
    width = info.bits // 8

    def pieces() -> Iterator[np.ndarray]:
        step = 1 << 18
        with open(path, "rb") as fh:
            fh.seek(info.data_offset)
            for start in range(0, info.frames, step):
                n = min(step, info.frames - start)
                raw = fh.read(n * width * info.channels)
                if len(raw) < n * width * info.channels:
                    raise AlignError("the file ends inside its samples", where=f"{path}: byte "
                                     f"{info.data_offset + start * width * info.channels + len(raw)}",
                                     hint="the file is truncated")
                yield _mono_int16(raw, info)

    return Source(str(path), info.rate, info.seconds, pieces())


def raw_source(handle, rate: int = RAW_RATE, name: str = "<stdin>") -> Source:
    """Raw PCM (:data:`RAW_FORMAT`) read from a binary file (standard input) as it comes."""
    if not 1000 <= rate <= 768_000:
        raise AlignError(f"raw PCM at {rate} Hz: the sample rate is out of range", where=name,
                         hint="give a rate (--pcm-rate) of 1000 to 768000 Hz")

    def pieces() -> Iterator[np.ndarray]:
        odd = b""
        while True:
            data = handle.read(1 << 16)
            if not data:
                break
            data = odd + data
            cut = len(data) - len(data) % 2
            odd = data[cut:]
            yield np.frombuffer(data[:cut], "<i2").astype(np.int16)

    return Source(name, rate, None, pieces())


def _quiet_cut(x: np.ndarray, start: int, stop: int, rate: int) -> int:
    """The sample at the quietest 10 ms of ``x[start:stop]``: between words, not inside one."""
    levels = frame_levels(x[start:stop].astype(np.float64) / 32768.0, rate)
    return start + int(np.argmin(levels)) * int(round(HOP * rate))


def _middle_pause(x: np.ndarray, rate: int) -> int | None:
    """Where to cut a lone block in two: the middle of the pause (at least :data:`PAUSE_SECONDS` without speech
    energy, :func:`~mpeg4fa.speech.align.recording.speech_frames`) nearest the block's middle within its middle
    half (the two halves take about as long to hear); None where there is none (the quietest moment of fluent
    speech is mostly a stop's closure, which a cut would split between two decodings)."""
    hop = int(round(HOP * rate))
    quiet = ~speech_frames(frame_levels(x.astype(np.float64) / 32768.0, rate))
    edges = np.flatnonzero(np.diff(np.concatenate([[0], quiet.astype(np.int8), [0]])))
    runs = edges.reshape(-1, 2)  # [start, stop) of each quiet run, in frames
    runs = runs[runs[:, 1] - runs[:, 0] >= int(round(PAUSE_SECONDS / HOP))]
    middles = (runs[:, 0] + runs[:, 1]) // 2 * hop
    inside = middles[(middles >= len(x) // 4) & (middles <= 3 * len(x) // 4)]
    return int(inside[np.argmin(np.abs(inside - len(x) // 2))]) if len(inside) else None


def blocks(source: Source, block_seconds: float = BLOCK_SECONDS) -> Iterator[tuple[float, Recording]]:
    """``(offset s, Recording)`` blocks of the source, each cut at a quiet moment (see the module docstring).
    The source's last block, when it would be heard alone (an even number of blocks before it) and lasts at
    least :data:`SPLIT_SECONDS`, is cut in two at the pause nearest its middle where it has one in its middle half
    (:func:`_middle_pause`), so that a clip shorter than a block is heard by both cores too (:func:`heard_blocks`);
    the cut depends on the audio alone, never on the cores."""
    rate = source.rate
    size = int(block_seconds * rate)
    window = int(CUT_SECONDS * rate)
    buffered: list[np.ndarray] = []
    held = count = 0
    offset = 0
    for piece in source.pieces:
        buffered.append(piece)
        held += len(piece)
        while held >= size + window:
            x = np.concatenate(buffered)
            cut = _quiet_cut(x, size - window, size, rate)
            yield offset / rate, Recording(x[:cut], rate, source.name)
            offset, count = offset + cut, count + 1
            buffered, held = [x[cut:]], len(x) - cut
    x = np.concatenate(buffered) if buffered else np.zeros(0, np.int16)
    cut = _middle_pause(x, rate) if count % 2 == 0 and len(x) >= SPLIT_SECONDS * rate else None
    if cut is not None:
        yield offset / rate, Recording(x[:cut], rate, source.name)
        offset, x = offset + cut, x[cut:]
    yield offset / rate, Recording(x, rate, source.name)


@dataclass(frozen=True)
class Heard:
    """What :func:`stream_listened` wrote: seconds of audio, frames, stream bytes, the recogniser, words
    heard, seconds of voice activity, blocks, notes, wall time."""

    seconds: float
    frames: int
    bytes: int
    recognizer: str
    words: int
    voiced: float
    blocks: int
    notes: tuple[str, ...]
    wall: float

    @property
    def silent(self) -> bool:
        return self.voiced == 0.0

    @property
    def speed(self) -> float:
        """Seconds of audio per second of wall time."""
        return self.seconds / self.wall if self.wall > 0 else float("inf")


def _timing_items(listened: Listened, timings, offset: float) -> list[dict]:
    """The timings as the JSON ``--timings`` writes (``encode``'s four keys), on the recording's clock, each
    with the ``word`` recognised over it where the words recogniser heard one."""
    words = listened.words
    out = []
    for t in timings:
        item = t.as_dict()
        item["start"], item["end"] = round(t.start + offset, 6), round(t.end + offset, 6)
        if words and t.viseme != PAUSE:
            mid = (t.start + t.end) / 2 + offset
            near = [w.word for w in words if w.start <= mid < w.end]
            if near:
                item["word"] = near[0]
        out.append(item)
    return out


def _helper_init() -> None:
    """In the helper process: Ctrl-C is the parent's to handle (it ends the helper), and a terminate
    ends it quietly (not through the parent's handlers, inherited by the fork)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    for name in ("SIGTERM", "SIGHUP"):
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), signal.SIG_DFL)


def _listen_block(rec: Recording, recognizer: str, lang: str) -> tuple[Listened, dict]:
    """:func:`.core.listen` in the helper, with the phonemes it showed by a guess (to be warned about once,
    by the parent: the helper's log is a copy)."""
    from mpeg4fa.speech.ipa import phoneme_fallbacks

    with phoneme_fallbacks() as log:
        before = {k: v[0] for k, v in log.seen.items()}
        heard = listen(rec, recognizer=recognizer, lang=lang)
    return heard, {k: [v[0] - before.get(k, 0), v[1], v[2]] for k, v in log.seen.items() if v[0] > before.get(k, 0)}


@contextlib.contextmanager
def _helper(wanted: bool) -> Iterator[list]:
    """A one-process pool for :func:`heard_blocks`, started when first asked for (``[pool]`` once started);
    none where the machine has one core or cannot fork (a spawned process would load the models again)."""
    import multiprocessing as mp

    started: list = []
    able = wanted and (os.cpu_count() or 1) >= 2 and "fork" in mp.get_all_start_methods()

    def start():
        if not started:
            started.append(mp.get_context("fork").Pool(1, initializer=_helper_init))
        return started[0]

    try:
        yield [start] if able else []
    finally:
        for pool in started:
            pool.terminate()
            pool.join()


def _listen_alone(rec: Recording, how: str, lang: str, helper: list) -> Listened:
    """A block heard with no other block beside it (a clip under :data:`SPLIT_SECONDS`, a last odd one, a clip with
    no pause in its middle half to cut at): with a ``helper`` and
    ``either`` still unsettled, the helper runs the phone loop (:func:`.core.phone_loop`) while this process
    decodes the words, so that a short clip too has both cores (the same result: the decoders are independent)."""
    if not helper or choose_recognizer(how, lang) != "either":
        return listen(rec, recognizer=how, lang=lang)
    active = voice_activity(rec.floats(), rec.rate)
    if not active.any():
        return listen(rec, recognizer=how, lang=lang, active=active)
    job = helper[0]().apply_async(phone_loop, (rec,))
    return listen(rec, recognizer=how, lang=lang, active=active, loop=job.get)


def _heard_as(rec: Recording, heard: Listened, how: str, lang: str) -> Listened:
    """``heard`` where ``either`` judged it as ``how`` on its own (or could not take the words path: no words
    aligned, or none heard), else ``rec`` heard again by ``how``, in this process (its own judgement kept as its
    confidence)."""
    if heard.recognizer == how or settled("either", heard) == how:  # (words judged, not alignable: phones kept)
        return heard
    if heard.confidence == float("-inf"):  # voice, but the word decoder heard no word in it: nothing to show by words
        return heard
    return replace(listen(rec, recognizer=how, lang=lang), confidence=heard.confidence)


def heard_blocks(source: Source, block_seconds: float, recognizer: str, lang: str, helper: list,
                 fallbacks) -> Iterator[tuple[float, Recording, Listened]]:
    """``(offset, block, Listened)`` in order, the blocks heard two by two. With a ``helper`` (:func:`_helper`) the
    two are heard at once, one in the helper process: pocketsphinx holds the GIL while it decodes (over 90 % of
    the time), so only a second process puts a second core to work; without one, one after the other, with the
    same recogniser, so that the recogniser each block takes does not depend on the cores. A last block alone is
    heard here (:func:`_listen_alone`: with ``either`` unsettled, its phone loop in the helper, else with no
    process started); ``fallbacks``: the :class:`~mpeg4fa.speech.ipa.FallbackLog` the helper's guessed phonemes
    join. ``either``: the first pair is judged together (:func:`.core.settled`) and that recogniser serves the
    whole recording: a block of the pair that took the other one is heard again."""
    held = None
    how = choose_recognizer(recognizer, lang)
    for offset, rec in blocks(source, block_seconds):
        if held is None:
            held = offset, rec
            continue
        if helper:
            job = helper[0]().apply_async(_listen_block, (held[1], how, lang))
            here = listen(rec, recognizer=how, lang=lang)
            there, guessed = job.get()
            for phoneme, (n, what, read_as) in guessed.items():
                fallbacks.seen.setdefault(phoneme, [0, what, read_as])[0] += n
        else:
            there = listen(held[1], recognizer=how, lang=lang)
            here = listen(rec, recognizer=how, lang=lang)
        if how == "either":  # the pair judged together: one recogniser for both, a half that took the other re-heard
            how = settled(how, there, here)
            there, here = _heard_as(held[1], there, how, lang), _heard_as(rec, here, how, lang)
        yield held[0], held[1], there
        yield offset, rec, here
        held = None
    if held is not None:
        yield held[0], held[1], _listen_alone(held[1], how, lang, helper)


def stream_listened(source: Source, out, *, timings=None, audio=None, recognizer: str = "auto", lang: str = "auto",
                    expression: tuple[str, int] | None = None, fps: float = 25.0, level: str = "high",
                    idle: bool = False, seed: int = 0, fold: bool = True, compact: bool = True, options=None,
                    progress: Progress | None = None, block_seconds: float = BLOCK_SECONDS,
                    two_cores: bool = True) -> Heard:
    """Hear ``source`` block by block and write its FBA stream to the binary file ``out`` (and the timed
    visemes as JSON to the text file ``timings``, the audio as 16-bit WAV to the binary file ``audio``).
    ``progress(done, total)`` counts seconds of audio (total 0 when a pipe's length is unknown).
    ``two_cores``: hear two blocks at once where the machine has the cores (:func:`heard_blocks`; the same
    recogniser each block, the phones path's stream byte for byte the same)."""
    from mpeg4fa.fba import EncodeOptions
    from mpeg4fa.speech.bits import FbaBlocks
    from mpeg4fa.speech.encoder import LEVELS, TEXT_CODING, StreamBuilder, closure_hold, phones
    from mpeg4fa.speech.frames import FrameMaker
    from mpeg4fa.speech.ipa import phoneme_fallbacks
    from mpeg4fa.wav import PcmWriter

    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    check_language(recognizer, lang)
    started = time.perf_counter()
    maker = FrameMaker(fps, idle=idle, seed=seed, closure_hold=closure_hold(fps), fields=level != "low")
    builder = StreamBuilder(level, fps, fold=fold, compact=compact)
    bits = FbaBlocks(out, builder.build, options if options is not None else EncodeOptions(**TEXT_CODING), fps,
                     place=lambda: (source.name, 1, 1))
    wav = PcmWriter(audio, source.rate, name=getattr(audio, "name", "<wav>")) if audio is not None else None
    listed = 0
    total = int(round(source.seconds)) if source.seconds is not None else 0
    end, words, voiced, count, used, notes = 0.0, 0, 0.0, 0, None, []
    if progress is not None:
        progress(0, total)
    try:
        with phoneme_fallbacks(source.name) as fallbacks, _helper(two_cores) as helper:
            for offset, rec, heard in heard_blocks(source, block_seconds, recognizer, lang, helper, fallbacks):
                utt = phones(heard.utterance)
                spans = viseme_spans([t.shifted(offset) for t in utt.timings])
                cues = expression_cues(expression) if count == 0 else ()
                end = offset + rec.duration
                bits.add(maker.add(spans, cues, end))
                if timings is not None:
                    for item in _timing_items(heard, utt.timings, offset):
                        text = json.dumps(item, ensure_ascii=False, indent=1).replace("\n", "\n ")
                        timings.write(("[\n " if not listed else ",\n ") + text)
                        listed += 1
                if wav is not None:
                    wav.write(rec.samples)
                words += len(heard.words)
                voiced += heard.voiced
                notes += [f"{offset:.1f} s: {n}" for n in heard.notes]
                used = heard.recognizer if used in (None, heard.recognizer) else "either"  # blocks differ
                count += 1
                if progress is not None:
                    progress(min(int(end), total) if total else int(end), total)
        bits.add(maker.finish(end))
        bits.finish()
    except BaseException:
        if wav is not None:
            wav.abandon()
        raise
    if wav is not None:
        wav.close()
    if timings is not None:
        timings.write("\n]\n" if listed else "[]\n")
    return Heard(end, bits.frames, bits.bytes, used or recognizer, words, voiced, count, tuple(notes),
                 time.perf_counter() - started)


def listened_whole(source: Source, *, recognizer: str = "auto", lang: str = "auto",
                   expression: tuple[str, int] | None = None, block_seconds: float = BLOCK_SECONDS,
                   two_cores: bool = True, max_seconds: float | None = None) -> Listened:
    """The source heard as :func:`stream_listened` hears it (the same blocks, two at once), as one
    :class:`~.core.Listened` on the recording's clock: what ``say`` renders, so that it shows what ``encode``
    writes. In memory (:func:`recording_of`: at most ``max_seconds``); ``recognizer``: ``either`` where the
    blocks took both; ``confidence``: the first block's own."""
    from mpeg4fa.speech.ipa import phoneme_fallbacks
    from mpeg4fa.speech.listen.core import ENGINE
    from mpeg4fa.speech.markup import Markup
    from mpeg4fa.speech.tts.base import Speech
    from mpeg4fa.speech.utterance import Utterance

    check_language(recognizer, lang)
    rec = recording_of(source, max_seconds)
    step = 1 << 18  # in pieces, as a file is read: blocks() copies what it holds at each cut
    whole = Source(source.name, rec.rate, rec.duration,
                   iter([rec.samples[i:i + step] for i in range(0, len(rec.samples), step)]))
    timings, events, words, notes, voiced, used, confidence = [], [], [], [], 0.0, None, float("nan")
    with phoneme_fallbacks(source.name) as fallbacks, _helper(two_cores) as helper:
        for offset, _block, heard in heard_blocks(whole, block_seconds, recognizer, lang, helper, fallbacks):
            timings += [t.shifted(offset) for t in heard.utterance.timings]
            events += [e.shifted(offset) for e in heard.utterance.speech.events]
            words += [replace(w, start=w.start + offset, end=w.end + offset) for w in heard.words]
            notes += [f"{offset:.1f} s: {n}" for n in heard.notes]
            voiced += heard.voiced
            confidence = heard.confidence if used is None else confidence
            used = heard.recognizer if used in (None, heard.recognizer) else "either"
    used = used or choose_recognizer(recognizer, lang)
    speech = Speech(rec.samples, rec.rate, tuple(sorted(events, key=lambda e: e.start)), ENGINE, f"recognised:{used}")
    markup = Markup(" ".join(w.word for w in words), ())
    utterance = Utterance(speech, tuple(timings), expression_cues(expression), markup)
    return Listened(utterance, used, tuple(words), voiced, tuple(notes), confidence)


def recording_of(source: Source, max_seconds: float | None = None) -> Recording:
    """The whole source as one :class:`Recording` (for what is rendered in memory: ``say``); AlignError
    past ``max_seconds`` (default the speech encoder's 30 min, :data:`mpeg4fa.wavread.MAX_SPEECH_SECONDS`)."""
    from mpeg4fa.wavread import MAX_SPEECH_SECONDS

    limit = MAX_SPEECH_SECONDS if max_seconds is None else max_seconds
    parts, held = [], 0
    for piece in source.pieces:
        parts.append(piece)
        held += len(piece)
        if held > limit * source.rate:
            raise AlignError(f"the recording lasts more than {limit / 60:g} min, more than is rendered at once",
                             where=source.name, hint="encode it to a stream with 'mpeg4fa encode --speech' (any "
                                                     "length), or cut it into parts")
    return Recording(np.concatenate(parts) if parts else np.zeros(0, np.int16), source.rate, source.name)
