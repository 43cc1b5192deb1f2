"""Viseme events from a cloud TTS (Azure Speech, Amazon Polly) -> the encoder's viseme timeline -> FAPs.

Azure and Polly speak the text themselves and say *when* each mouth shape starts; this module reads
those events and hands them to the same path as our own speech (:func:`.encoder.encode_utterance`:
Hermite moves across each boundary, closures held, FAP 1 or low-level FAPs), so the stream shows the
mouth as it would for espeak-ng's phoneme events.

Accepted files (``format="auto"`` tells them apart by their keys):

* **Azure** ``VisemeReceived`` events logged as JSON: an array (or ``{"visemes": [...]}`` /
  ``{"events": [...]}``) of objects with the audio offset in ticks of 100 ns and the viseme ID
  0..21: ``{"AudioOffset": 500000, "VisemeId": 21}``; the SDKs' other spellings ``audioOffset`` /
  ``visemeId``, ``audio_offset`` / ``viseme_id`` and the JavaScript SDK's ``privAudioOffset`` /
  ``privVisemeId`` are read too, and other keys (``Animation``) are ignored;
* **Polly** speech marks: JSON lines (or a JSON array) ``{"time": 6, "type": "viseme", "value": "p"}``
  with the time in milliseconds; marks of other types (word, sentence, ssml) are skipped.

IDs and Polly visemes become MPEG-4 visemes through ``spec/azure_visemes.csv`` and
``spec/polly_visemes.csv`` (:mod:`mpeg4fa.spec.avatars`); Azure's diphthong IDs (9 aʊ, 10 ɔɪ, 11 aɪ)
become two, the nucleus for the first :data:`~mpeg4fa.speech.ipa.FIRST_SHARE` of the event's time and
the offglide for the rest, as the IPA route splits a diphthong. Each event's viseme lasts until the next
event; silence (Azure 0, Polly ``sil``) is a pause; the last viseme lasts :data:`LAST_VISEME` unless
an event ends it, and the stream runs :data:`TAIL` past the last event so the mouth comes to rest.
There is no audio: the stream goes with the TTS's own.

Errors are :class:`~mpeg4fa.formats.FormatError` located in the file: ``path:line:column`` for
broken JSON, ``path:line`` and the event's index (0-based, among the file's events) for a bad time
or viseme.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mpeg4fa import jsonio
from mpeg4fa.formats.errors import FormatError
from mpeg4fa.spec.avatars import AZURE_VISEMES, from_azure, from_polly
from mpeg4fa.spec.errors import SpecError
from mpeg4fa.speech.markup import Markup
from mpeg4fa.speech.tts.base import Speech
from mpeg4fa.speech.utterance import Timing, Utterance
from mpeg4fa.speech.ipa import FIRST_SHARE
from mpeg4fa.speech.visemes import PAUSE
from mpeg4fa.wavread import MAX_SPEECH_SECONDS

__all__ = ["VisemeEvent", "FORMATS", "LAST_VISEME", "TAIL", "MAX_SECONDS", "MAX_EVENTS", "MAX_BYTES", "TICKS_PER_SECOND", "parse_viseme_events",
           "read_viseme_events", "events_utterance", "encode_viseme_events", "stream_viseme_events"]

FORMATS = ("auto", "azure", "polly")
TICKS_PER_SECOND = 10_000_000
"""Azure's audio offsets are in ticks of 100 ns."""
LAST_VISEME = 0.15
"""Seconds the last viseme lasts when no event (silence) ends it: about one spoken phoneme."""
TAIL = 0.2
"""Seconds the stream runs past the end of the last viseme, long enough for the mouth to reach rest."""
MAX_SECONDS = MAX_SPEECH_SECONDS
"""Events later than this (30 min, :data:`mpeg4fa.wavread.MAX_SPEECH_SECONDS`, as for a ``--speech``
recording) are refused, before anything is allocated: :func:`encode_viseme_events` codes them in memory
(:func:`.encoder.encode_utterance`), in time and memory that grow with the duration (an event just under
1 h took 10.7 s and 655 MB through ``encode --visemes``), and a time that large is a unit mistake (a cloud
TTS request gives minutes of speech). ``encode --visemes`` streams (:func:`stream_viseme_events`): 30 min
take about 4 s and 285 MB there."""
MAX_EVENTS = 200_000
"""Most events (or speech marks) a file may hold: half an hour of speech has about 25,000 visemes."""
MAX_BYTES = 32 << 20
"""Largest viseme event file read (32 MiB): 200,000 events of Polly's verbose marks."""
_RATE = 1000  # sample rate of the silent audio that only gives the utterance its duration
_AZURE_KEYS = (("AudioOffset", "VisemeId"), ("audioOffset", "visemeId"), ("audio_offset", "viseme_id"),
               ("privAudioOffset", "privVisemeId"))


@dataclass(frozen=True)
class VisemeEvent:
    """From ``time`` (seconds in the TTS audio) the mouth shows MPEG-4 ``viseme`` (``none``: silence)."""

    time: float
    viseme: str
    source: str
    """What the file said: the Azure ID or Polly viseme, e.g. ``"21"`` or ``"p"``."""
    line: int | None = None
    """The file's line of this event, where known."""
    index: int = 0
    """Its index among the file's events or marks (0-based), as errors name it."""
    offglide: str | None = None
    """A diphthong's second viseme (Azure 9, 10, 11): the last part of the event's time shows it."""


def _records(text: str | bytes, name: str) -> list[tuple[dict, int | None]]:
    """The file's objects and their line: a JSON array, an object holding one, or JSON lines.

    Read by :mod:`mpeg4fa.jsonio` (size, nesting, encoding and numbers checked, every fault located);
    at most :data:`MAX_EVENTS` records.
    """
    if not (text if isinstance(text, str) else text.decode("utf-8", "replace")).strip(" \t\r\n\ufeff"):
        raise FormatError(name, None, None, "the file is empty", hint="give Azure or Polly viseme events as JSON")
    try:
        data = jsonio.loads(text, name, max_bytes=MAX_BYTES, error=FormatError, what="viseme events")
    except FormatError as exc:
        if not exc.problem.startswith("invalid JSON: Extra data"):
            raise
        records = [(item, number) for number, item in jsonio.loads_lines(
            text, name, max_bytes=MAX_BYTES, error=FormatError, what="Polly speech marks (JSON lines)")]
        return _counted(records, name)
    if isinstance(data, list):
        if len(data) > MAX_EVENTS:
            _too_many(len(data), name)
        source = text if isinstance(text, str) else jsonio.decode_utf8(text, name, FormatError)
        return list(zip(data, _item_lines(source)))
    if isinstance(data, dict):
        for key in ("visemes", "events", "speechMarks", "marks"):
            if isinstance(data.get(key), list):
                return _counted([(item, None) for item in data[key]], name)
        return [(data, 1)]
    raise FormatError(name, 1, 1, f"JSON {type(data).__name__} where a list of events was expected",
                      hint="a JSON array of events, or JSON lines")


def _counted(records: list[tuple[dict, int | None]], name: str) -> list[tuple[dict, int | None]]:
    if len(records) > MAX_EVENTS:
        _too_many(len(records), name)
    return records


def _too_many(n: int, name: str) -> None:
    raise FormatError(name, None, None, f"{n:,} events, more than the {MAX_EVENTS:,} read",
                      hint=f"a viseme event file covers at most {MAX_SECONDS / 60:g} min of speech; split it")


def _item_lines(text: str) -> list[int]:
    """The line each item of a top-level JSON array (already parsed, so well formed) starts on.

    Line starts are found once (:class:`~mpeg4fa.jsonio.LineIndex`), so this is linear in the text.
    """
    decoder = json.JSONDecoder()
    index = jsonio.LineIndex(text)
    lines, at = [], text.index("[") + 1
    while True:
        while text[at] in " \t\r\n,":
            at += 1
        if text[at] == "]":
            return lines
        lines.append(index.line(at))
        at = decoder.raw_decode(text, at)[1]


def _guess(records: list[tuple[dict, int | None]], name: str) -> str:
    for item, _ in records:
        if isinstance(item, dict):
            if any(time in item and vid in item for time, vid in _AZURE_KEYS):
                return "azure"
            if "time" in item and "type" in item:
                return "polly"
    raise FormatError(name, None, None, "cannot tell Azure viseme events from Polly speech marks",
                      hint="Azure: {\"AudioOffset\": ticks, \"VisemeId\": 0-21}; Polly: {\"time\": ms, "
                           "\"type\": \"viseme\", \"value\": \"p\"}; or pass the format")


def _place(name: str, line: int | None, index: int, problem: str, hint: str) -> FormatError:
    return FormatError(name, line, None, f"event {index}: {problem}", hint=hint)


def _number(value: object, per_second: float) -> float | None:
    """Seconds of a time given in units of 1/``per_second`` s, or None when it is no time up to MAX_SECONDS."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    seconds = float(value) / per_second
    return seconds if math.isfinite(seconds) and 0 <= seconds <= MAX_SECONDS else None


def _azure_event(item: object, line: int | None, index: int, name: str) -> VisemeEvent:
    hint = "Azure events are {\"AudioOffset\": ticks of 100 ns, \"VisemeId\": 0-21}"
    if not isinstance(item, dict):
        raise _place(name, line, index, f"JSON {type(item).__name__} is not an event object", hint)
    keys = next(((t, v) for t, v in _AZURE_KEYS if t in item and v in item), None)
    if keys is None:
        raise _place(name, line, index, f"no audio offset and viseme ID among the keys {sorted(item)}", hint)
    seconds = _number(item[keys[0]], TICKS_PER_SECOND)
    if seconds is None:
        raise _place(name, line, index, f"{keys[0]} {item[keys[0]]!r} is not a time (ticks 0..{MAX_SECONDS:g} s)",
                     hint)
    vid = item[keys[1]]
    try:
        viseme = from_azure(vid)
    except SpecError as exc:
        raise _place(name, line, index, exc.message, exc.hint) from None
    return VisemeEvent(seconds, viseme, str(vid), line, index, AZURE_VISEMES[vid].offglide)


def _polly_event(item: object, line: int | None, index: int, name: str) -> VisemeEvent | None:
    hint = "Polly viseme marks are {\"time\": ms, \"type\": \"viseme\", \"value\": \"p\"}"
    if not isinstance(item, dict):
        raise _place(name, line, index, f"JSON {type(item).__name__} is not a speech mark", hint)
    if item.get("type") != "viseme":
        if "type" not in item:
            raise _place(name, line, index, "a speech mark without a type", hint)
        return None
    seconds = _number(item.get("time"), 1000.0)
    if seconds is None:
        raise _place(name, line, index, f"time {item.get('time')!r} is not a time (ms 0..{MAX_SECONDS:g} s)", hint)
    try:
        viseme = from_polly(item.get("value"))
    except SpecError as exc:
        raise _place(name, line, index, exc.message, exc.hint) from None
    return VisemeEvent(seconds, viseme, str(item.get("value")), line, index)


def parse_viseme_events(text: str | bytes, name: str = "<events>", format: str = "auto"
                        ) -> tuple[str, list[VisemeEvent]]:
    """``(format, events)`` of a viseme event file's text (or bytes), in time order (see the module docstring).

    Times past :data:`MAX_SECONDS` and more than :data:`MAX_EVENTS` events are refused here, before the
    encoder allocates anything for them.
    """
    if format not in FORMATS:
        raise ValueError(f"format {format!r}: one of {', '.join(FORMATS)}")
    records = _records(text, name)
    kind = _guess(records, name) if format == "auto" else format
    reader = _azure_event if kind == "azure" else _polly_event
    events = [e for k, (item, line) in enumerate(records) if (e := reader(item, line, k, name)) is not None]
    if not events:
        raise FormatError(name, None, None, f"no {kind} viseme events in the file",
                          hint="Polly: request speech mark type viseme; Azure: log the VisemeReceived events")
    for k in range(1, len(events)):
        if events[k].time < events[k - 1].time:
            e = events[k]
            raise _place(name, e.line, e.index, f"time {e.time:.3f} s is before the previous event's "
                         f"{events[k - 1].time:.3f} s", "events must be in time order, as the TTS sends them")
    return kind, events


def read_viseme_events(path: str | Path, format: str = "auto") -> tuple[str, list[VisemeEvent]]:
    """:func:`parse_viseme_events` of a file (UTF-8, at most :data:`MAX_BYTES`; a bad byte is located)."""
    name = str(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_BYTES + 1)
    except OSError as exc:
        raise FormatError.from_os_error(name, exc) from None
    return parse_viseme_events(data, name, format)


def events_utterance(events: list[VisemeEvent], engine: str = "events", name: str = "<events>") -> Utterance:
    """An :class:`Utterance` of the events, silent audio covering them: what the encoder's timeline takes."""
    timings = []
    for k, e in enumerate(events):
        end = events[k + 1].time if k + 1 < len(events) else e.time + (0.0 if e.viseme == PAUSE else LAST_VISEME)
        if end <= e.time:
            continue
        if e.offglide is None:
            timings.append(Timing(phoneme=e.source, viseme=e.viseme, start=e.time, end=end))
        else:  # a diphthong: the nucleus first, the offglide late, as the IPA route splits one
            split = e.time + FIRST_SHARE * (end - e.time)
            timings += [Timing(phoneme=e.source, viseme=e.viseme, start=e.time, end=split),
                        Timing(phoneme=e.source, viseme=e.offglide, start=split, end=end)]
    duration = (timings[-1].end if timings else events[-1].time) + TAIL
    speech = Speech(np.zeros(int(math.ceil(duration * _RATE)), np.int16), _RATE, (), engine, "")
    return Utterance(speech=speech, timings=tuple(timings), cues=(), markup=Markup("", (), name=name))


def stream_viseme_events(events: list[VisemeEvent], out, *, timings=None, engine: str = "events", fps: float = 25.0,
                         level: str = "high", idle: bool = False, seed: int = 0, options=None, name: str = "<events>"):
    """The events' stream written to the binary file ``out`` block by block (and the timed visemes to the text
    file ``timings``): :func:`.pipeline.stream_utterance`, what ``encode --visemes`` runs; a
    :class:`~.pipeline.Spoken` says what was written."""
    from mpeg4fa.speech.pipeline import stream_utterance

    return stream_utterance(events_utterance(events, engine, name), out, timings=timings, fps=fps, level=level,
                            idle=idle, seed=seed, options=options, name=name)


def encode_viseme_events(events: list[VisemeEvent], *, engine: str = "events", fps: float = 25.0,
                         level: str = "high", idle: bool = False, seed: int = 0, name: str = "<events>"):
    """The :class:`~mpeg4fa.speech.encoder.Encoded` stream of the events, as text is encoded."""
    from mpeg4fa.speech.encoder import encode_utterance

    return encode_utterance(events_utterance(events, engine, name), fps=fps, level=level, idle=idle, seed=seed)

