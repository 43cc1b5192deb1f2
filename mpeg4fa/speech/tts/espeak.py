"""espeak-ng through its C API (ctypes), the engine that gives sample-exact phoneme timing.

Only the C API reports *when* each phoneme starts in the audio (``espeak_EVENT.sample``); the
command line and pyttsx3 do not. Phoneme names come as espeak's mnemonics (``tS``, ``aI``: what
``spec/english_visemes.csv`` is written in) or, with ``synthesize(..., ipa=True)``, in IPA
(``tʃ``, ``aɪ``: what :mod:`mpeg4fa.speech.ipa` reads for any language), switched per synthesis
with ``espeak_ng_SetPhonemeEvents``: the same phonemes one for one, timed alike (up to the ~10 ms
espeak's timing wanders between any two syntheses). The library and its data come from the
``espeakng_loader`` wheel (espeak-ng 1.52): Debian's 1.51 reads Mandarin tone digits as English
numbers.

espeak-ng is one global state per process, so it is initialised once (module level) and every
synthesis holds one lock. Do not use pyttsx3 in the same process: it drives the same instance.
"""
from __future__ import annotations

import bisect
import ctypes
import html
import os
import re
import threading
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable, Sequence

import numpy as np

from mpeg4fa.atomic import signals_deferred
from mpeg4fa.speech.errors import TTSError
from mpeg4fa.speech.tts.base import Event, Speech

WHERE = "espeak"
DEFAULT_VOICE = "en-us"
DEFAULT_RATE = 175
RATE_RANGE = (80, 450)  # espeakRATE_MINIMUM .. espeakRATE_MAXIMUM (words per minute)

# speak_lib.h constants
AUDIO_OUTPUT_SYNCHRONOUS = 2
POS_CHARACTER = 1
espeakINITIALIZE_PHONEME_EVENTS = 0x0001
espeakCHARS_UTF8 = 0x1
espeakSSML = 0x10
espeakENDPAUSE = 0x1000
espeakRATE = 1
EE_OK = 0

EV_LIST_TERMINATED = 0
EV_WORD = 1
EV_SENTENCE = 2
EV_MARK = 3
EV_PLAY = 4
EV_END = 5  # end of clause or sentence
EV_MSG_TERMINATED = 6
EV_PHONEME = 7
EV_SAMPLERATE = 8


def phoneme_name(raw: bytes) -> str:
    """A phoneme name from the event's 8 bytes: up to the first NUL; an IPA name longer than 8 bytes
    arrives cut, so an incomplete UTF-8 character at the end is dropped rather than shown as U+FFFD."""
    name = raw.split(b"\0", 1)[0]
    for cut in range(4):  # a UTF-8 character is at most 4 bytes
        try:
            return name[:len(name) - cut].decode("utf-8")
        except UnicodeDecodeError:
            continue
    return name.decode("utf-8", "replace")


class _EventId(ctypes.Union):
    """``espeak_EVENT.id``: a number (word, sentence), a name (mark) or an 8-byte phoneme name."""

    _fields_ = [
        ("number", ctypes.c_int),
        ("name", ctypes.c_char_p),
        ("string", ctypes.c_char * 8),
    ]


class EspeakEvent(ctypes.Structure):
    """``espeak_EVENT`` as laid out on 64-bit Linux: six 4-byte ints, a pointer at offset 24,
    the 8-byte union at offset 32; 40 bytes in all."""

    _fields_ = [
        ("type", ctypes.c_int),
        ("unique_identifier", ctypes.c_uint),
        ("text_position", ctypes.c_int),
        ("length", ctypes.c_int),
        ("audio_position", ctypes.c_int),
        ("sample", ctypes.c_int),
        ("user_data", ctypes.c_void_p),
        ("id", _EventId),
    ]


class EspeakVoice(ctypes.Structure):
    """``espeak_VOICE``; ``languages`` is a list of (priority byte, NUL-ended name), 0-ended."""

    _fields_ = [
        ("name", ctypes.c_char_p),
        ("languages", ctypes.c_void_p),
        ("identifier", ctypes.c_char_p),
        ("gender", ctypes.c_ubyte),
        ("age", ctypes.c_ubyte),
        ("variant", ctypes.c_ubyte),
        ("xx1", ctypes.c_ubyte),
        ("score", ctypes.c_int),
        ("spare", ctypes.c_void_p),
    ]


SYNTH_CALLBACK = ctypes.CFUNCTYPE(
    ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.POINTER(EspeakEvent)
)


@dataclass
class RawEvent:
    """One espeak event copied out of the callback (the C memory is reused after it returns)."""

    type: int
    text_position: int
    length: int
    audio_position: int
    sample: int
    number: int = 0
    name: str = ""


@dataclass
class _Collector:
    """Where the callback puts one synthesis' PCM chunks and events."""

    chunks: list[np.ndarray] = field(default_factory=list)
    events: list[RawEvent] = field(default_factory=list)
    error: BaseException | None = None
    stopped: Callable[[], bool] = lambda: False  # a signal came (Ctrl-C, SIGTERM): abort the synthesis


_lock = threading.RLock()
_lib: ctypes.CDLL | None = None
_sample_rate = 0
_data_path = ""
_collector: _Collector | None = None
_callback_ref = None  # keeps the C function pointer alive for the life of the process


def _on_synth(wav, n: int, events) -> int:
    """Copy audio and events out; never raise into C (store the error, raise after)."""
    col = _collector
    if col is None:
        return 0
    try:
        if wav and n > 0:
            col.chunks.append(np.ctypeslib.as_array(wav, shape=(n,)).astype(np.int16, copy=True))
        if events:
            i = 0
            while True:
                ev = events[i]
                if ev.type == EV_LIST_TERMINATED:
                    break
                raw = RawEvent(ev.type, ev.text_position, ev.length, ev.audio_position, ev.sample)
                if ev.type == EV_PHONEME:
                    raw.name = phoneme_name(bytes(ev.id.string))
                elif ev.type in (EV_MARK, EV_PLAY):
                    raw.name = (ev.id.name or b"").decode("utf-8", "replace")
                else:
                    raw.number = ev.id.number
                col.events.append(raw)
                i += 1
    except BaseException as exc:  # noqa: BLE001 - must not cross into C
        if col.error is None:
            col.error = exc
    return 1 if col.error is not None or col.stopped() else 0  # 1: espeak stops synthesising


def _load() -> ctypes.CDLL:
    """Load and initialise the wheel's libespeak-ng once per process (caller holds ``_lock``)."""
    global _lib, _sample_rate, _callback_ref, _data_path
    if _lib is not None:
        return _lib
    hint = "install the espeakng-loader wheel (pip install espeakng-loader==0.2.4)"
    try:
        import espeakng_loader
    except ImportError as exc:
        raise TTSError(f"espeakng_loader is not installed ({exc})", where=WHERE, hint=hint) from exc
    try:
        lib_path = str(espeakng_loader.get_library_path())
        data_path = str(espeakng_loader.get_data_path())
        lib = ctypes.CDLL(lib_path)
    except OSError as exc:
        raise TTSError(f"cannot load libespeak-ng ({exc})", where=WHERE, hint=hint) from exc

    lib.espeak_Initialize.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_char_p, ctypes.c_int]
    lib.espeak_Initialize.restype = ctypes.c_int
    lib.espeak_SetSynthCallback.argtypes = [SYNTH_CALLBACK]
    lib.espeak_SetSynthCallback.restype = None
    lib.espeak_SetVoiceByName.argtypes = [ctypes.c_char_p]
    lib.espeak_SetVoiceByName.restype = ctypes.c_int
    lib.espeak_SetParameter.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int]
    lib.espeak_SetParameter.restype = ctypes.c_int
    lib.espeak_Synth.argtypes = [
        ctypes.c_void_p, ctypes.c_size_t, ctypes.c_uint, ctypes.c_int, ctypes.c_uint,
        ctypes.c_uint, ctypes.POINTER(ctypes.c_uint), ctypes.c_void_p,
    ]
    lib.espeak_Synth.restype = ctypes.c_int
    lib.espeak_Synchronize.argtypes = []
    lib.espeak_Synchronize.restype = ctypes.c_int
    lib.espeak_SetVoiceByProperties.argtypes = [ctypes.POINTER(EspeakVoice)]
    lib.espeak_SetVoiceByProperties.restype = ctypes.c_int
    lib.espeak_ListVoices.argtypes = [ctypes.POINTER(EspeakVoice)]
    lib.espeak_ListVoices.restype = ctypes.POINTER(ctypes.POINTER(EspeakVoice))
    lib.espeak_GetCurrentVoice.argtypes = []
    lib.espeak_GetCurrentVoice.restype = ctypes.POINTER(EspeakVoice)
    lib.espeak_ng_SetPhonemeEvents.argtypes = [ctypes.c_int, ctypes.c_int]
    lib.espeak_ng_SetPhonemeEvents.restype = ctypes.c_int

    rate = lib.espeak_Initialize(
        AUDIO_OUTPUT_SYNCHRONOUS, 0, data_path.encode(), espeakINITIALIZE_PHONEME_EVENTS
    )
    if rate <= 0:
        raise TTSError(
            f"espeak_Initialize failed (returned {rate}) with data path {data_path}",
            where=WHERE, hint="reinstall the espeakng-loader wheel; its espeak-ng-data may be damaged",
        )
    _callback_ref = SYNTH_CALLBACK(_on_synth)
    lib.espeak_SetSynthCallback(_callback_ref)
    _lib, _sample_rate, _data_path = lib, rate, data_path
    return lib


def _languages(ptr: int | None) -> tuple[str, ...]:
    """Decode espeak's packed language list: (priority byte, NUL-ended name)*, then a 0 byte."""
    if not ptr:
        return ()
    out: list[str] = []
    offset = 0
    while ctypes.c_ubyte.from_address(ptr + offset).value != 0 and len(out) < 32:
        name = ctypes.string_at(ptr + offset + 1)
        out.append(name.decode("utf-8", "replace"))
        offset += 2 + len(name)
    return tuple(out)


_EMOJI_JOINERS = re.compile("[\u200d\u20e3\ufe0e\ufe0f\U0001f1e6-\U0001f1ff\U0001f3fb-\U0001f3ff\U000e0020-\U000e007f]")
"""The parts that join emoji into sequences: zero-width joiner, the keycap, variation selectors, regional
indicators (flags), skin tones and tag characters (subdivision flags)."""


def _without_emoji_joiners(text: str) -> str:
    """``text`` with every emoji-joining code point a space (one character for one: offsets stay).

    espeak-ng 1.52 corrupts memory on some such sequences: the Scottish Gaelic voice (``gd``) on
    ``#`` + U+FE0F + U+20E3 + ``ý`` + a flag (two regional indicators) dies with SIGSEGV (found by the
    fuzz campaign, ``text:88775@0``). The emoji themselves stay (a voice may name them); what joins them
    into keycaps, flags and families is not speech.
    """
    return _EMOJI_JOINERS.sub(" ", text)


MAX_VARIANT_BYTES = 32
"""Longest ``+variant`` of a voice name handed to espeak-ng: it copies ``!v/`` and the variant into a 40-byte
buffer, and from 37 bytes the fortified C library aborts the whole process ("buffer overflow detected", exit 134;
measured 2026-12-07 on Debian's 1.51). Its own variants are 2-12 bytes."""


def check_voice_name(voice: str, where: str = WHERE) -> None:
    """TTSError for a voice whose variant espeak-ng cannot take without crashing (:data:`MAX_VARIANT_BYTES`)."""
    variant = voice.partition("+")[2]
    size = len(variant.encode("utf-8", "surrogatepass"))
    if size > MAX_VARIANT_BYTES:
        shown = variant if len(variant) <= 20 else variant[:20] + "..."
        raise TTSError(f"the voice variant {shown!r} is {size} bytes long; espeak-ng takes at most "
                       f"{MAX_VARIANT_BYTES}", where=where, hint="use a variant 'mpeg4fa voices' lists, e.g. en-us+f3")


def _c_string(name: str) -> bytes | None:
    """``name`` as the C library takes it (UTF-8, no NUL), or None: a voice so named cannot exist (a lone
    surrogate, from a command-line byte that is not UTF-8, has no UTF-8 at all)."""
    try:
        code = name.encode("utf-8")
    except UnicodeEncodeError:
        return None
    return None if b"\0" in code else code


def _set_voice_by_language(lib, language: str) -> bool:
    """Choose a voice by language code ("en-gb"): voice files are named by case-sensitive paths."""
    code = _c_string(language)
    if not code or any(c in code for c in b"/ "):
        return False
    spec = EspeakVoice()
    spec.languages = ctypes.cast(ctypes.c_char_p(code), ctypes.c_void_p)
    return lib.espeak_SetVoiceByProperties(ctypes.byref(spec)) == EE_OK and _voice_is(lib, language)


def _set_voice_by_file(lib, language: str) -> bool:
    """Last resort: the file of a listed voice that speaks ``language`` (codes espeak's own search misses,
    like ``chr-US-Qaaa-x-west``)."""
    for v in voices(speaking=True):
        if language.lower() in (code.lower() for code in v.languages) and v.identifier:
            if lib.espeak_SetVoiceByName(v.identifier.encode("utf-8")) == EE_OK:
                return True
    return False


def _voice_is(lib, language: str) -> bool:
    """espeak falls back to a default voice rather than failing: check the language it took."""
    current = lib.espeak_GetCurrentVoice()
    return bool(current) and language.lower() in (lang.lower() for lang in _languages(current.contents.languages))


def list_voices() -> list[tuple[str, tuple[str, ...]]]:
    """All installed voices as (name, languages); a voice can be chosen by name or language."""
    with _lock:
        lib = _load()
        table = lib.espeak_ListVoices(None)
        out: list[tuple[str, tuple[str, ...]]] = []
        i = 0
        while table and table[i]:
            v = table[i].contents
            out.append(((v.name or b"").decode("utf-8", "replace"), _languages(v.languages)))
            i += 1
    return out


@dataclass(frozen=True)
class Voice:
    """One installed espeak-ng voice: its first language code (what ``--lang`` and ``--voice`` take),
    its name, its file (``identifier``, also accepted as a voice), every language it speaks, and the
    pronunciation dictionary it reads (``dictionary``; ``speaks``: whether that file is installed)."""

    language: str
    name: str
    identifier: str
    languages: tuple[str, ...]
    dictionary: str = ""
    speaks: bool = True

    def as_dict(self) -> dict:
        return {"language": self.language, "name": self.name, "identifier": self.identifier,
                "languages": list(self.languages), "dictionary": self.dictionary}


def _voice_dictionary(data_path: str, identifier: str, language: str) -> tuple[str, bool]:
    """The dictionary a voice file names and whether ``NAME_dict`` is in the data: espeak-ng's rule (its
    first ``language`` line up to the first ``-``, unless a ``dictionary`` line names one). A voice whose
    dictionary is missing (``fo``, ``kaa``, ``xex`` in the espeakng-loader wheel) is listed by espeak-ng but
    cannot speak: loading it prints "Can't read dictionary file" on stderr and falls back to no phonemes."""
    name = language.split("-")[0]
    for folder in ("lang", "voices"):
        try:
            with open(os.path.join(data_path, folder, identifier), encoding="utf-8", errors="replace") as handle:
                lines = handle.read(1 << 16).splitlines()
        except (OSError, ValueError):
            continue
        first_language = True
        for line in lines:
            words = line.split("//", 1)[0].split()
            if len(words) >= 2 and words[0] == "language" and first_language and words[1] != "variant":
                name, first_language = words[1].split("-")[0], False
            elif len(words) >= 2 and words[0] == "dictionary":
                name = words[1]
        break
    else:  # no voice file where expected: say nothing against it
        return name, True
    return name, bool(name) and os.path.isfile(os.path.join(data_path, f"{name}_dict"))


@lru_cache(maxsize=1)
def _all_voices() -> tuple[Voice, ...]:
    with _lock:
        lib = _load()
        table = lib.espeak_ListVoices(None)
        out: list[Voice] = []
        i = 0
        while table and table[i]:
            v = table[i].contents
            langs = _languages(v.languages)
            language = langs[0] if langs else ""
            identifier = (v.identifier or b"").decode("utf-8", "replace")
            dictionary, speaks = _voice_dictionary(_data_path, identifier, language)
            out.append(Voice(language, (v.name or b"").decode("utf-8", "replace"), identifier, langs,
                             dictionary, speaks))
            i += 1
    return tuple(sorted(out, key=lambda v: (v.language, v.name)))


def voices(*, speaking: bool = False) -> list[Voice]:
    """Every installed voice, sorted by language code then name; ``speaking``: only those whose dictionary
    is installed (the list ``mpeg4fa voices`` prints)."""
    return [v for v in _all_voices() if v.speaks or not speaking]


def missing_dictionary(voice: str) -> str | None:
    """The dictionary ``voice`` (a voice's language code, name or file, ``+variant`` allowed) would need and
    this installation lacks, when every voice it names lacks it; None when it can speak (or names none)."""
    key = voice.split("+", 1)[0].strip().lower()
    named = [v for v in _all_voices() if key and (
        key in (v.name.lower(), v.identifier.lower(), v.identifier.lower().rsplit("/", 1)[-1])
        or key in (code.lower() for code in v.languages))]
    if named and not any(v.speaks for v in named):
        return named[0].dictionary
    return None


@lru_cache(maxsize=1)
def language_codes() -> frozenset[str]:
    """Every language code some installed voice speaks (lower case): ``es``, ``fr-fr``, ``yue``..."""
    return frozenset(code.lower() for v in voices() for code in v.languages)


def _voice_hint(voice: str) -> str:
    """A few voices close to the one asked for, so the error says what to write instead."""
    voices = list_voices()
    key = voice.lower().split("-")[0][:2]
    close = [lang for _, langs in voices for lang in langs if lang.lower().startswith(key)]
    common = ["en-us", "en-gb", "cmn", "cmn-latn-pinyin", "fr-fr", "de", "es", "ja"]
    names = list(dict.fromkeys(close + common))[:10]
    return f"try one of: {', '.join(names)} ({len(voices)} voices installed; see list_voices())"


def _ssml_with_marks(text: str, marks: Sequence[tuple[int, str]]) -> tuple[str, list[int], dict[str, str]]:
    """Escape ``text`` for XML and insert ``<mark name=.../>`` at each offset.

    Returns the SSML; for each SSML character index (plus one past the end) the plain-text
    offset it came from, so positions espeak reports can be mapped back; and the mark names
    used in the SSML -> the caller's names. espeak hands attribute values back still escaped,
    so the SSML carries plain generated names (``m0``, ``m1``...) instead of the caller's.
    """
    by_offset: dict[int, list[str]] = {}
    names: dict[str, str] = {}
    for k, (offset, name) in enumerate(marks):
        tag_name = f"m{k}"
        names[tag_name] = name
        by_offset.setdefault(offset, []).append(tag_name)
    parts: list[str] = []
    back: list[int] = []
    for i in range(len(text) + 1):
        for tag_name in by_offset.get(i, ()):
            tag = f'<mark name="{tag_name}"/>'
            parts.append(tag)
            back.extend([i] * len(tag))
        if i < len(text):
            piece = html.escape(text[i], quote=False)
            parts.append(piece)
            back.extend([i] * len(piece))
    back.append(len(text))
    return "".join(parts), back, names


class EspeakEngine:
    """espeak-ng speech with phoneme, word, sentence and mark events timed to the sample.

    Voices: ``en-us`` (default) for English, ``cmn`` for hanzi, ``cmn-latn-pinyin`` for pinyin
    with tone digits. Phoneme ``text`` is espeak's mnemonic (``h``, ``@``, ``oU``; pauses start
    with ``_``); Mandarin phonemes carry no tones.
    """

    name = "espeak"
    speaks_ipa = True
    """``synthesize(..., ipa=True)`` names phonemes in IPA (what :mod:`mpeg4fa.speech.utterance` checks)."""

    def __init__(self, voice: str = DEFAULT_VOICE, rate: int = DEFAULT_RATE, *,
                 keep_stress: bool = False) -> None:
        self.voice = voice
        self.rate = rate
        # espeak prefixes stressed vowels with ' (primary) or , (secondary); visemes do not care
        self.keep_stress = keep_stress

    def languages(self) -> frozenset[str]:
        """The language codes the installed voices speak (lower case; see :func:`language_codes`)."""
        return language_codes()

    @property
    def sample_rate(self) -> int:
        """The library's output rate (22050 Hz for espeak-ng voices)."""
        with _lock:
            _load()
            return _sample_rate

    def synthesize(
        self,
        text: str,
        *,
        voice: str | None = None,
        rate: int | None = None,
        marks: Sequence[tuple[int, str]] = (),
        ipa: bool = False,
    ) -> Speech:
        """Speak ``text`` and return the audio with its events (see ``Engine.synthesize``).

        ``ipa``: phoneme events named in IPA instead of espeak's mnemonics (the same phonemes).

        Marks go in as SSML ``<mark/>``s; put them between words: espeak splits a word at a
        mark inside it (and pronounces the halves separately).
        """
        global _collector
        voice = voice or self.voice
        wpm = self.rate if rate is None else rate
        if not isinstance(text, str) or not text.strip():
            raise TTSError("nothing to say: the text is empty", where=WHERE,
                           hint="pass some words to synthesize")
        if "\0" in text:
            raise TTSError("the text contains a NUL character", where=WHERE,
                           hint="remove NUL characters from the text")
        from mpeg4fa.speech.chunks import MAX_RUN, long_run  # the parse pass cuts text there; others are checked

        run = long_run(text)
        if run is not None:  # espeak-ng 1.52 overruns a buffer on ~200 dotted letters: never hand it such a run
            raise TTSError(f"{len(run.group()):,} characters without a space at character {run.start() + 1}: "
                           f"espeak-ng speaks at most {MAX_RUN} at a time", where=WHERE,
                           hint="put spaces in the run (text given to encode or say is cut there by itself)")
        if not RATE_RANGE[0] <= int(wpm) <= RATE_RANGE[1]:
            raise TTSError(f"rate {wpm} words per minute is out of range", where=WHERE,
                           hint=f"use {RATE_RANGE[0]}..{RATE_RANGE[1]} (default {DEFAULT_RATE})")
        marks = [(int(o), str(n)) for o, n in marks]
        for offset, name in marks:
            if not 0 <= offset <= len(text):
                raise TTSError(f"mark {name!r} at offset {offset} is outside the text",
                               where=WHERE, hint=f"offsets run 0..{len(text)}")
            if not name:
                raise TTSError("a mark has an empty name", where=WHERE, hint="name every mark")

        text = _without_emoji_joiners(text)
        flags = espeakCHARS_UTF8 | espeakENDPAUSE
        if marks:
            source, back, mark_names = _ssml_with_marks(text, marks)
            flags |= espeakSSML
        else:
            source, back, mark_names = text, list(range(len(text) + 1)), {}

        check_voice_name(voice)
        name = _c_string(voice)
        with _lock:
            lib = _load()
            dictionary = missing_dictionary(voice) if name is not None else None
            if dictionary is not None:  # refused before espeak-ng tries it (and prints on stderr)
                raise TTSError(f"espeak-ng has no dictionary for {voice} in this installation "
                               f"({dictionary}_dict is missing)", where=WHERE,
                               hint="choose another voice: 'mpeg4fa voices' lists those that speak")
            if name is None or (lib.espeak_SetVoiceByName(name) != EE_OK and not _set_voice_by_language(lib, voice)
                                and not _set_voice_by_file(lib, voice)):
                raise TTSError(f"unknown voice {voice!r}", where=WHERE, hint=_voice_hint(voice))
            lib.espeak_SetParameter(espeakRATE, int(wpm), 0)
            col = _collector = _Collector()
            lib.espeak_ng_SetPhonemeEvents(1, 1 if ipa else 0)
            try:
                data = source.encode("utf-8") + b"\0"
                buf = ctypes.create_string_buffer(data, len(data))
                with signals_deferred() as col.stopped:  # Ctrl-C/SIGTERM in the callback would be lost
                    err = lib.espeak_Synth(buf, len(data), 0, POS_CHARACTER, 0, flags, None, None)
                if err != EE_OK:
                    raise TTSError(f"espeak_Synth failed with status {err}", where=WHERE,
                                   hint="retry; if it persists the text may be too long")
                lib.espeak_Synchronize()
            finally:
                _collector = None
                if ipa:
                    lib.espeak_ng_SetPhonemeEvents(1, 0)
            rate_hz = _sample_rate
        if col.error is not None:
            raise TTSError(f"event callback failed: {col.error!r}", where=WHERE,
                           hint="this is a bug in the ctypes binding") from col.error

        samples = np.concatenate(col.chunks) if col.chunks else np.zeros(0, np.int16)
        events = _to_events(col.events, text, back, len(samples), rate_hz,
                            keep_stress=self.keep_stress, mark_names=mark_names)
        return Speech(samples=samples, rate=rate_hz, events=events, engine=self.name, voice=voice)


STRESS_MARKS = "',\u02c8\u02cc"
"""Stress marks in front of a phoneme name: espeak's mnemonics (' and ,) and IPA's (ˈ and ˌ)."""


def _extend_word(text: str, stop: int, limit: int) -> int:
    """espeak can report a short length for a word it read as one unit (Mandarin 你好 has
    length 1): grow it over letters, never past the next word's start."""
    while stop < limit and text[stop].isalnum():
        stop += 1
    return stop


def _to_events(raw: list[RawEvent], text: str, back: list[int], n: int, rate: int, *,
               keep_stress: bool = False, mark_names: dict[str, str] | None = None,
               ) -> tuple[Event, ...]:
    """Turn espeak's raw events into ``Event``s: seconds from samples, plain-text positions,
    interval ends from the next event of the same kind (or the end of the audio).

    espeak's synchronous mode never delivers its end-of-message event, so the ``end`` event is
    added at the end of the audio when missing. End-of-clause events are dropped: the pause
    phonemes already mark clause ends.
    """
    total = n / rate

    def plain(pos: int) -> int:
        # text_position counts characters from 1 in the string espeak read (0: none); the
        # closing pauses point past the end of the text, which is no position at all
        idx = pos - 1
        if idx < 0 or idx >= len(back) - 1:
            return -1
        return back[idx]

    word_positions = sorted({plain(ev.text_position) for ev in raw if ev.type == EV_WORD})
    sentence_positions = sorted({plain(ev.text_position) for ev in raw if ev.type == EV_SENTENCE})

    def following(positions: list[int], p: int) -> int:
        """The first position after ``p`` (where the next word or sentence starts)."""
        k = bisect.bisect_right(positions, p)
        return positions[k] if k < len(positions) else len(text)
    mark_names = mark_names or {}

    def at(sample: int) -> float:
        return min(max(sample, 0), n) / rate

    starts: list[tuple[str, float, str, int]] = []
    for ev in raw:
        t = at(ev.sample)
        if ev.type == EV_PHONEME:
            name = ev.name if keep_stress else ev.name.lstrip(STRESS_MARKS) or ev.name
            starts.append(("phoneme", t, name, plain(ev.text_position)))
        elif ev.type == EV_WORD:
            p = plain(ev.text_position)
            word = ""
            if p >= 0:
                stop = min(ev.text_position - 1 + max(ev.length, 0), len(back) - 1)
                limit = following(word_positions, p)  # numbers split into sub-words
                word = text[p:_extend_word(text, min(max(back[stop], p), limit), limit)].strip()
            starts.append(("word", t, word, p))
        elif ev.type == EV_SENTENCE:
            p = plain(ev.text_position)
            limit = following(sentence_positions, p)
            starts.append(("sentence", t, text[p:limit].strip() if p >= 0 else "", p))
        elif ev.type == EV_MARK:
            starts.append(("mark", t, mark_names.get(ev.name, ev.name), plain(ev.text_position)))
        elif ev.type == EV_MSG_TERMINATED:
            starts.append(("end", t, "", -1))

    if not any(s[0] == "end" for s in starts):
        starts.append(("end", total, "", -1))

    out: list[Event] = []
    next_start = {"phoneme": total, "word": total, "sentence": total}
    for kind, t, label, pos in reversed(starts):  # one pass: each interval ends at the next start
        end = t
        if kind in next_start:
            end = max(next_start[kind], t)
            next_start[kind] = t
        out.append(Event(kind, t, end, label, pos))
    out.reverse()
    out.sort(key=lambda e: e.start)  # stable: espeak's order among equal times is kept
    return tuple(out)
