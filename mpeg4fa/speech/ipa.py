"""IPA phonemes -> the 14 MPEG-4 visemes, through articulatory features (any espeak-ng language).

Why features: a hand-made phoneme list covers one voice; espeak-ng speaks about a hundred
languages and reports every phoneme in IPA. An IPA segment's features (rounding, height and
backness for a vowel; place and manner for a consonant) say what the mouth does, so one
table of segments and one ordered list of rules cover them all. The data live in ``spec/``:

* ``ipa_features.csv``: one row per IPA base segment (facts of the IPA chart);
* ``ipa_visemes.csv``: our rules, tried in order, first match wins (an empty cell matches
  anything, ``;`` separates alternatives);
* ``ipa_aliases.csv``: characters some voices send for IPA letters (espeak's own ASCII
  mnemonics where a voice defines no IPA name, ``ʦ`` digraphs, Greek look-alikes) and the IPA
  they stand for;
* ``ipa_marks.csv``: diacritics, length, stress and tone marks: dropped, or ``round`` (the
  segment they follow counts as rounded: ``ɯᵝ``); ``alone`` is what a mark stands for when
  espeak sends it as a phoneme of its own (``ʲ`` after a Russian consonant: ``=``, the
  previous phoneme continues).

An espeak phoneme event may hold several segments: a diphthong (``aɪ``), an affricate
(``tʃ``), a long vowel spelt twice (``aa``). Equal visemes next to each other merge; the rest
split the phoneme's time: the first part takes :data:`FIRST_SHARE` (a diphthong's nucleus),
except the stop of an affricate, which takes :data:`AFFRICATE_STOP_SHARE` (a short release;
the fricative carries the sound); the remaining parts share the rest equally. Inside one
phoneme an ``ɹ`` or ``ɻ`` after a vowel is that vowel's r-colouring (espeak writes ``ɑːɹ``,
``ɛɹ`` for r-coloured vowels), dropped like the rhotic hook ``˞``.

An empty event is a pause (espeak's ``_``) when the audio is silent there; espeak also leaves
a few short sounding phonemes without an IPA name (English ``;`` after ``I2``, the Russian
epenthetic ``@-`` between p and r): there the previous phoneme continues, as
``spec/english_visemes.csv`` has it for ``;``. A parenthesised event (``(en)``) is a language
switch inside the text: the previous phoneme continues.

A character the tables do not know never stops the speech (espeak-ng grows; a mouth that stops
is worse than a near one): :func:`nearest` reads it as the closest thing they do know (its
compatibility form, ``ᵊ`` -> ``ə``; the base letter its Unicode name gives, ``ʞ`` TURNED K -> ``k``,
Greek alpha -> ``ɑ``; a combining mark or symbol is dropped; any other letter is a schwa), and every
such phoneme is counted in one :class:`~mpeg4fa.speech.errors.PhonemeWarning` per encode
(:func:`phoneme_fallbacks`), naming each with what it was read as, so the table can be completed.

espeak hands a phoneme name over in 8 bytes; a longer IPA string arrives cut, its last
incomplete character dropped by the engine binding (its marks matter little; a cut base
letter loses its viseme part).
"""
from __future__ import annotations

import unicodedata
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from mpeg4fa.spec import VISEME_PROFILES
from mpeg4fa.spec._load import read_table, split_list
from mpeg4fa.speech.errors import PhonemeWarning, TTSError
from mpeg4fa.speech.tts.base import Event

PAUSE = "none"
CONTINUE = "="
SOUNDING_DB = -40.0
"""Mean level (dBFS) above which an unnamed phoneme is sound, not a pause."""
FIRST_SHARE = 0.7
"""The first part of a split phoneme (a diphthong's nucleus: the offglide is a movement towards a target
reached late). Halves would agree with the English table on 91.6 % of frames, 60/40 on 92.9 %, 70/30 on 94.0 %
(spec/README.md)."""
AFFRICATE_STOP_SHARE = 0.3
"""The stop of an affricate (t of tʃ, ts): the fricative that follows carries the sound."""

RHOTIC = frozenset("ɹɻ")
"""Approximants that, after a vowel in the same phoneme, are its r-colouring."""
KINDS = ("vowel", "consonant")
HEIGHTS = ("close", "near-close", "close-mid", "mid", "open-mid", "near-open", "open")
BACKNESS = ("front", "central", "back")
PLACES = ("bilabial", "labiodental", "dental", "alveolar", "postalveolar", "retroflex", "alveolopalatal",
          "palatal", "labial-palatal", "velar", "labial-velar", "uvular", "pharyngeal", "epiglottal", "glottal")
MANNERS = ("stop", "nasal", "trill", "tap", "fricative", "approximant", "lateral-approximant",
           "lateral-fricative", "lateral-tap", "implosive", "click")
_ACTIONS = ("drop", "round")
ANY_LETTER = "ə"
"""What a letter nothing else identifies is read as: the most neutral vowel (viseme E)."""
_LISTED = 6
"""Phonemes named in the fallback warning; the rest are counted."""


@dataclass(frozen=True)
class Segment:
    """One IPA base segment and its articulatory features (``rounded`` after marks like ``ᵝ``)."""

    symbol: str
    kind: str
    height: str = ""
    backness: str = ""
    rounded: bool = False
    place: str = ""
    manner: str = ""
    voiced: bool = True


@dataclass(frozen=True)
class Mark:
    """A diacritic or suprasegmental: ``drop`` or ``round``; ``alone``: its meaning as a phoneme of its own."""

    char: str
    action: str
    alone: str
    name: str


@dataclass(frozen=True)
class Rule:
    """One row of ``ipa_visemes.csv``: feature sets to match (empty: any) -> viseme."""

    kind: str
    place: tuple[str, ...]
    manner: tuple[str, ...]
    height: tuple[str, ...]
    backness: tuple[str, ...]
    rounded: bool | None
    viseme: str

    def matches(self, s: Segment) -> bool:
        def ok(allowed: tuple[str, ...], value: str) -> bool:
            return not allowed or value in allowed
        return (s.kind == self.kind and ok(self.place, s.place) and ok(self.manner, s.manner)
                and ok(self.height, s.height) and ok(self.backness, s.backness)
                and (self.rounded is None or self.rounded == s.rounded))


def _bit(text: str, where: str) -> bool:
    if text not in ("0", "1"):
        raise ValueError(f"{where}: expected 0 or 1, got {text!r}")
    return text == "1"


def _one_of(value: str, allowed: tuple[str, ...], where: str, empty: bool) -> str:
    if (value or not empty) and value not in allowed:
        raise ValueError(f"{where}: {value!r} is not one of {', '.join(allowed)}")
    return value


@lru_cache(maxsize=None)
def features() -> dict[str, Segment]:
    """``spec/ipa_features.csv``: IPA segment -> its features (checked: known values, no repeats)."""
    out: dict[str, Segment] = {}
    rows = read_table("ipa_features.csv", "segment,kind,height,backness,rounded,place,manner,voiced,note")
    for line, r in enumerate(rows, start=2):
        where = f"spec/ipa_features.csv:{line}"
        symbol = r["segment"]
        if len(symbol) != 1 or symbol in out:
            raise ValueError(f"{where}: segment {symbol!r} must be one character, listed once")
        kind = _one_of(r["kind"], KINDS, where, empty=False)
        vowel = kind == "vowel"
        out[symbol] = Segment(
            symbol, kind, _one_of(r["height"], HEIGHTS, where, empty=not vowel),
            _one_of(r["backness"], BACKNESS, where, empty=not vowel), _bit(r["rounded"], where),
            _one_of(r["place"], PLACES, where, empty=vowel), _one_of(r["manner"], MANNERS, where, empty=vowel),
            _bit(r["voiced"], where))
    for s in out.values():
        viseme_of(s)  # every segment must reach a viseme: fail at load, not in the middle of a sentence
    return out


@lru_cache(maxsize=None)
def rules() -> tuple[Rule, ...]:
    """``spec/ipa_visemes.csv``, in order (first match wins)."""
    out = []
    rows = read_table("ipa_visemes.csv", "kind,place,manner,height,backness,rounded,viseme,note")
    for line, r in enumerate(rows, start=2):
        where = f"spec/ipa_visemes.csv:{line}"
        _one_of(r["kind"], KINDS, where, empty=False)
        lists = {}
        for column, allowed in (("place", PLACES), ("manner", MANNERS), ("height", HEIGHTS),
                                ("backness", BACKNESS)):
            lists[column] = split_list(r[column])
            for value in lists[column]:
                _one_of(value, allowed, f"{where} ({column})", empty=False)
        if r["viseme"] not in VISEME_PROFILES["mpeg4"]:
            raise ValueError(f"{where}: unknown viseme {r['viseme']!r}")
        rounded = None if r["rounded"] == "" else _bit(r["rounded"], where)
        out.append(Rule(r["kind"], lists["place"], lists["manner"], lists["height"], lists["backness"], rounded,
                        r["viseme"]))
    return tuple(out)


@lru_cache(maxsize=None)
def aliases() -> dict[str, str]:
    """``spec/ipa_aliases.csv``: a character some voice sends -> the IPA it stands for."""
    out: dict[str, str] = {}
    known = features()
    for line, r in enumerate(read_table("ipa_aliases.csv", "char,ipa,note"), start=2):
        where = f"spec/ipa_aliases.csv:{line}"
        char, ipa = r["char"], r["ipa"]
        if len(char) != 1 or char in out or char in known:
            raise ValueError(f"{where}: {char!r} must be one character, listed once, and no segment of "
                             "spec/ipa_features.csv")
        if not ipa or any(c not in known for c in ipa):
            raise ValueError(f"{where}: {ipa!r} must be segments of spec/ipa_features.csv")
        out[char] = ipa
    return out


@lru_cache(maxsize=None)
def marks() -> dict[str, Mark]:
    """``spec/ipa_marks.csv``: mark character -> what to do with it."""
    out: dict[str, Mark] = {}
    for line, r in enumerate(read_table("ipa_marks.csv", "codepoint,action,alone,name"), start=2):
        where = f"spec/ipa_marks.csv:{line}"
        code = r["codepoint"]
        if not code.startswith("U+"):
            raise ValueError(f"{where}: codepoint {code!r} must read U+XXXX")
        char = chr(int(code[2:], 16))
        if char in out:
            raise ValueError(f"{where}: {code} is listed twice")
        _one_of(r["action"], _ACTIONS, where, empty=False)
        out[char] = Mark(char, r["action"], r["alone"], r["name"])
    known = features()
    for m in out.values():
        if m.alone not in ("", CONTINUE) and m.alone not in known:
            raise ValueError(f"spec/ipa_marks.csv: U+{ord(m.char):04X} stands alone for {m.alone!r}, "
                             "which is no segment of spec/ipa_features.csv")
        if m.char in known:
            raise ValueError(f"spec/ipa_marks.csv: {m.char!r} is a segment in spec/ipa_features.csv as well")
    return out


def viseme_of(segment: Segment) -> str:
    """The viseme of one segment: the first rule of ``ipa_visemes.csv`` it matches."""
    for rule in rules():
        if rule.matches(segment):
            return rule.viseme
    raise ValueError(f"spec/ipa_visemes.csv: no rule matches {segment.symbol!r} ({segment})")


def nearest(char: str) -> str:
    """What a character no table knows is read as: one IPA segment or alias of the tables, or ``""`` (dropped).

    In order: its compatibility form (superscripts, small and full-width forms: ``ᵊ`` -> ``ə``); the
    base letter its Unicode name gives, without ``WITH ...`` and leading words such as ``TURNED``,
    ``SMALL CAPITAL`` (``ʞ`` -> ``k``; a Greek or Cyrillic letter whose name is a Latin IPA letter's:
    alpha -> ``ɑ``); its lower case; then by class: any other letter is :data:`ANY_LETTER`, anything
    else (a combining mark, a modifier letter, punctuation, a digit, a symbol) is dropped.
    """
    known, alias = features(), aliases()

    def usable(c: str) -> bool:
        return c in known or c in alias

    for c in unicodedata.normalize("NFKD", char):
        if c != char and usable(c):
            return c
    name = unicodedata.name(char, "")
    if " LETTER " in f" {name} ":
        words = name.split("LETTER ", 1)[1].split(" WITH ", 1)[0].split()
        for k in range(len(words)):
            try:
                base = unicodedata.lookup("LATIN SMALL LETTER " + " ".join(words[k:]))
            except KeyError:
                continue
            if base != char and usable(base):
                return base
    if usable(char.lower()):
        return char.lower()
    if unicodedata.category(char) in ("Lu", "Ll", "Lt", "Lo"):
        return ANY_LETTER
    return ""


def parse(text: str) -> tuple[list[Segment], list[str]]:
    """The segments of one phoneme's IPA, and the characters the tables do not know.

    Marks are applied to the segment before them (or taken alone when the phoneme is nothing
    but marks); a precomposed letter the table lacks is tried as its decomposition (``ä`` =
    ``a`` + diaeresis); ``ç`` and other letters the table lists are never decomposed. A character
    still unknown is listed and read as :func:`nearest` says, so the segments are never short of it.
    """
    known, mark_table, alias = features(), marks(), aliases()
    out: list[Segment] = []
    unknown: list[str] = []
    alone: list[str] = []

    def take(ch: str) -> None:
        if ch in known:
            out.append(known[ch])
            return
        if ch in alias:
            for part in alias[ch]:
                take(part)
            return
        mark = mark_table.get(ch)
        if mark is not None:
            if mark.action == "round" and out:
                s = out[-1]
                out[-1] = Segment(s.symbol, s.kind, s.height, s.backness, True, s.place, s.manner, s.voiced)
            if mark.alone:
                alone.append(mark.alone)
            return
        parts = unicodedata.normalize("NFD", ch)
        if len(parts) > 1:
            for part in parts:
                take(part)
            return
        unknown.append(ch)
        for part in nearest(ch):
            take(part)

    for ch in text:
        take(ch)
    if not out and alone:
        first = alone[0]
        return ([] if first == CONTINUE else [known[first]]), unknown
    return out, unknown


def phoneme_visemes(text: str) -> tuple[list[tuple[str, str]], list[str]]:
    """(segment symbol, viseme) parts of one phoneme event with equal neighbours merged, and unknown characters.

    An empty name is a pause (``[("", "none")]``); a language switch ``(xx)`` or a lone ``ʲ`` is
    ``[("", "=")]``: the previous phoneme continues. Unknown characters are read as :func:`nearest`
    says, so the parts are always there; the list says which characters were guessed.
    """
    bare = text.strip()
    if not bare:
        return [("", PAUSE)], []
    if bare.startswith("(") and bare.endswith(")"):
        return [("", CONTINUE)], []
    segments, unknown = parse(bare)
    if not segments:
        return [("", CONTINUE)], unknown
    segments = [s for k, s in enumerate(segments)
                if not (k > 0 and s.symbol in RHOTIC and segments[k - 1].kind == "vowel")]
    parts: list[tuple[str, str]] = []
    for s in segments:
        v = viseme_of(s)
        if parts and parts[-1][1] == v:
            parts[-1] = (parts[-1][0] + s.symbol, v)
            continue
        parts.append((s.symbol, v))
    return parts, unknown


def shares(first: Segment | None, second: Segment | None, n: int) -> list[float]:
    """How a phoneme's time is split over its ``n`` parts (see the module docstring)."""
    if n <= 1:
        return [1.0]
    lead = FIRST_SHARE
    if (first is not None and second is not None and first.kind == second.kind == "consonant"
            and first.manner == "stop" and second.manner == "fricative"):
        lead = AFFRICATE_STOP_SHARE
    return [lead] + [(1.0 - lead) / (n - 1)] * (n - 1)


def sounding(samples: np.ndarray, rate: int) -> Callable[[Event], bool]:
    """A test of whether the audio is sound (not silence) over an event (see :data:`SOUNDING_DB`)."""
    x = np.asarray(samples, dtype=np.float64) / 32768.0

    def test(event: Event) -> bool:
        a, b = int(round(event.start * rate)), int(round(event.end * rate))
        if b <= a:
            return False
        power = float(np.mean(x[a:b] ** 2))
        return power > 0 and 10 * np.log10(power) > SOUNDING_DB
    return test


@dataclass
class FallbackLog:
    """Phonemes shown by a guess (:func:`nearest`) during one encode: phoneme -> [count, characters, read as]."""

    where: str = "espeak"
    seen: dict[str, list] = field(default_factory=dict)

    def note(self, phoneme: str, unknown: list[str] | str, read_as: str) -> None:
        """Count one phoneme; ``unknown``: the characters guessed, or a phrase saying what was unknown."""
        what = unknown if isinstance(unknown, str) else " ".join(f"U+{ord(c):04X}" for c in dict.fromkeys(unknown))
        entry = self.seen.setdefault(phoneme, [0, what, read_as])
        entry[0] += 1

    def __len__(self) -> int:
        return sum(entry[0] for entry in self.seen.values())

    def message(self) -> str:
        """One line: how many, and the first few phonemes with their unknown characters and what they became."""
        def one(phoneme: str, count: int, what: str, read_as: str) -> str:
            return f"{phoneme!r} x{count} ({what}; read as {read_as or 'nothing'})"
        listed = [one(p, *entry) for p, entry in list(self.seen.items())[:_LISTED]]
        more = len(self.seen) - _LISTED
        n = len(self)
        return (f"{self.where}: {n} phoneme{'s' if n != 1 else ''} with symbols the phoneme tables do not know "
                f"showed the nearest viseme by features: " + ", ".join(listed)
                + (f" and {more} more" if more > 0 else ""))


_fallbacks: ContextVar[FallbackLog | None] = ContextVar("phoneme_fallbacks", default=None)


@contextmanager
def phoneme_fallbacks(where: str = "espeak") -> Iterator[FallbackLog]:
    """Collect the phonemes shown by a guess and say them in one :class:`PhonemeWarning` at the end.

    Nested uses share the outermost log, so an encode that wraps all its runs (or sentences) warns
    once; :func:`ipa_visemes` and :func:`mpeg4fa.speech.visemes.english_visemes` open one themselves,
    so a caller that wraps nothing gets one warning per call. No warning when the block raises.
    """
    outer = _fallbacks.get()
    if outer is not None:
        yield outer
        return
    log = FallbackLog(where)
    token = _fallbacks.set(log)
    try:
        yield log
    finally:
        _fallbacks.reset(token)
    if log.seen:
        warnings.warn(log.message(), PhonemeWarning, stacklevel=3)


def split_event(event: Event, parts: list[tuple[str, str]]) -> list[tuple[str, str, float, float]]:
    """(label, viseme, start, end) of one phoneme's parts over its time (:func:`shares`); a one-part phoneme is
    labelled by its name, the parts of a split one as ``name:segment``."""
    if len(parts) == 1:
        return [(event.text, parts[0][1], event.start, event.end)]
    known = features()
    heads = [known.get(p[0][:1]) for p in parts]
    cut = shares(heads[0], heads[1], len(parts))
    out, t = [], event.start
    for k, ((symbol, viseme), share) in enumerate(zip(parts, cut)):
        # the last part ends exactly where the phoneme does: the sum of the shares, rounded, can land an ulp
        # past it, into the next phoneme (the timeline refuses overlapping spans)
        stop = event.end if k == len(parts) - 1 else min(t + share * (event.end - event.start), event.end)
        out.append((f"{event.text}:{symbol}", viseme, t, stop))
        t = stop
    return out


def ipa_visemes(phonemes: list[Event], where: str = "espeak", is_sound: Callable[[Event], bool] | None = None,
                ) -> list[tuple[str, str, float, float]]:
    """(label, viseme, start, end) for espeak's IPA phoneme events, diphthongs and affricates split.

    A one-part phoneme is labelled by its IPA; the parts of a split one as ``IPA:segment``. An
    unnamed event is a pause, or with ``is_sound`` saying it is sound, the previous phoneme continued.
    Never fails on a character the tables lack: it shows the nearest viseme (:func:`nearest`) and is
    counted in the :func:`phoneme_fallbacks` warning.
    """
    out: list[tuple[str, str, float, float]] = []
    with phoneme_fallbacks(where) as log:
        for event in phonemes:
            if not event.text.strip() and is_sound is not None and is_sound(event):
                out.append((event.text, out[-1][1] if out else PAUSE, event.start, event.end))
                continue
            parts, unknown = phoneme_visemes(event.text)
            if unknown:
                log.note(event.text, unknown, "".join(symbol for symbol, _ in parts))
            if len(parts) == 1 and parts[0][1] == CONTINUE:
                out.append((event.text, out[-1][1] if out else PAUSE, event.start, event.end))
                continue
            out += split_event(event, parts)
    return out


def frame_agreement(reference, other, duration: float, fps: float = 25.0) -> tuple[float, int]:
    """Share of frames where two timings (anything with ``viseme``, ``start``, ``end``) show the same viseme.

    Frames are sampled at their centres over ``duration``; frames where both show a pause are left
    out (they would agree trivially). Returns (share, frames compared). Used to hold the IPA route
    to the English table (the reference) on English speech.
    """
    times = (np.arange(int(np.floor(duration * fps))) + 0.5) / fps

    def at(timings) -> list[str]:
        shown = [PAUSE] * len(times)
        for t in timings:
            for k in np.flatnonzero((times >= t.start) & (times < t.end)):
                shown[k] = t.viseme
        return shown

    pairs = [(a, b) for a, b in zip(at(reference), at(other)) if not (a == PAUSE and b == PAUSE)]
    if not pairs:
        return float("nan"), 0
    return sum(a == b for a, b in pairs) / len(pairs), len(pairs)


@dataclass(frozen=True)
class _Span:
    viseme: str
    start: float
    end: float


def english_agreement(engine, texts: list[str], fps: float = 25.0, voice: str = "en-us") -> tuple[float, int]:
    """How often the IPA route shows the English table's viseme on English speech: (share of frames, frames).

    Each text is spoken twice, once with espeak's mnemonics (mapped by ``spec/english_visemes.csv``,
    the reference) and once in IPA (mapped here). espeak's timing wanders by up to ~10 ms from one
    synthesis to the next, which alone would flip frames, so the IPA events are put on the mnemonic
    run's times (the two runs give the same phonemes, one for one): what is compared is the mapping
    and the splitting, frame by frame (:func:`frame_agreement`).
    """
    from mpeg4fa.speech.visemes import english_visemes

    agree = frames = 0.0
    for text in texts:
        reference = engine.synthesize(text, voice=voice)
        named = engine.synthesize(text, voice=voice, ipa=True)
        ref_events, ipa_events = list(reference.phonemes()), list(named.phonemes())
        if len(ref_events) != len(ipa_events):
            raise TTSError(f"the two runs of {text[:40]!r} gave {len(ref_events)} and {len(ipa_events)} phonemes",
                           where=engine.name, hint="this comparison needs one phoneme list")
        retimed = [Event("phoneme", r.start, r.end, i.text, r.position) for r, i in zip(ref_events, ipa_events)]
        table = [_Span(v, e.start, e.end) for v, e in english_visemes(ref_events)]
        route = [_Span(v, a, b) for _, v, a, b in
                 ipa_visemes(retimed, where=engine.name, is_sound=sounding(reference.samples, reference.rate))]
        share, n = frame_agreement(table, route, reference.duration, fps)
        agree, frames = agree + share * n, frames + n
    return (agree / frames if frames else float("nan")), int(frames)
