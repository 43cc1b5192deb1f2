"""Tagged text spoken: one audio track, the visemes it shows, and when each tag takes effect.

Text is cut into runs by script. Latin runs go to an English voice and map their
phonemes through ``spec/english_visemes.csv``. Hanzi runs (with CJK punctuation)
are read as pinyin (:mod:`.mandarin`, phrase-aware, tones kept) and spoken by
espeak-ng's pinyin voice, which reports one word event per syllable; inside a
syllable the initial takes the time of its consonant phoneme, and the glide, main
vowel and ending share the rest by the engine's phoneme boundaries when the counts
match, else by fixed weights. Runs are spoken separately and joined, so mixed
Chinese/English text works.

Any other espeak-ng language (``lang="es"``, or a Cyrillic, Arabic, Devanagari or kana run
under ``auto``, see :func:`.script.runs`) takes the IPA route: espeak names its phonemes in IPA
and :mod:`.ipa` maps them to the 14 MPEG-4 visemes by their articulatory features. English and
Mandarin keep their own tables (the reference); ``route="ipa"`` sends English through the IPA
route too, to compare the two. A tag's time is a mark event placed at its offset
(or, when the engine drops or cannot send marks, the start of the next word).

Engines that time words but no phonemes (pyttsx3, the silent estimator) get their
visemes from the spelling or the pinyin (:mod:`.graphemes`), timed by estimate
and resynchronised at every word or syllable boundary (:mod:`.wordsync`).
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from mpeg4fa.speech.errors import MarkupError, TTSError
from mpeg4fa.speech.ipa import ipa_visemes, sounding
from mpeg4fa.speech.graphemes import SYLLABLE_UNIT, english_units, seconds_per_unit, syllable_units
from mpeg4fa.speech.mandarin import FINAL_WEIGHT, Syllable, final_roles, syllables
from mpeg4fa.speech.markup import Markup
from mpeg4fa.speech.script import check_speakable, runs
from mpeg4fa.speech.timeline import ExpressionCue, VisemeSpan
from mpeg4fa.speech.tts.base import Engine, Event, Speech, snap_to_tokens, word_tokens
from mpeg4fa.speech.visemes import PAUSE, english_visemes
from mpeg4fa.speech.wordsync import resync

ENGLISH_VOICE = "en-us"
PINYIN_VOICE = "cmn-latn-pinyin"
LANGS = ("auto", "en", "zh")
"""The languages every engine takes; engines with IPA phoneme events take any espeak-ng language code too."""
ROUTES = ("reference", "ipa")
_PUNCT = {"，": ", ", "、": ", ", "；": "; ", "：": ": ", "。": ". ", "！": "! ", "？": "? ", "…": "... "}


@dataclass(frozen=True)
class Timing:
    """One viseme interval and the phoneme (or pinyin part) it came from, in the audio's seconds."""

    phoneme: str
    viseme: str
    start: float
    end: float
    set: str = "mpeg4"

    def shifted(self, seconds: float) -> "Timing":
        """The same interval ``seconds`` later (a part's timing on the whole's clock)."""
        return Timing(self.phoneme, self.viseme, self.start + seconds, self.end + seconds, self.set)

    def as_dict(self) -> dict:
        return {"phoneme": self.phoneme, "viseme": self.viseme, "start": round(self.start, 6),
                "end": round(self.end, 6)}


def viseme_spans(timings: Iterable[Timing]) -> list[VisemeSpan]:
    """Viseme spans of ``timings`` for the timeline: pauses left out, repeats of one viseme that touch joined
    (the rule :meth:`Utterance.spans` and the recording-only path share)."""
    out: list[VisemeSpan] = []
    for t in timings:
        if t.viseme == PAUSE or t.end <= t.start:
            continue
        if out and out[-1].viseme == t.viseme and out[-1].set == t.set and abs(out[-1].end - t.start) < 1e-9:
            out[-1] = VisemeSpan(t.viseme, out[-1].start, t.end, t.set)
        else:
            out.append(VisemeSpan(t.viseme, t.start, t.end, t.set))
    return out


@dataclass(frozen=True)
class Utterance:
    speech: Speech
    timings: tuple[Timing, ...]
    cues: tuple[ExpressionCue, ...]
    markup: Markup

    def spans(self) -> list[VisemeSpan]:
        """Viseme spans for the timeline: pauses left out, repeats of one viseme joined."""
        return viseme_spans(self.timings)


def speaks_ipa(engine: Engine) -> bool:
    """Whether ``engine`` names phonemes in IPA on request (``synthesize(..., ipa=True)``)."""
    return bool(getattr(engine, "speaks_ipa", False))


def check_language(lang: str, engine: Engine) -> None:
    """Refuse a language ``engine`` cannot speak, with one line saying what to do instead."""
    if lang in LANGS:
        return
    if not isinstance(lang, str) or not lang.strip() or lang != lang.strip():
        raise TTSError(f"unknown language {lang!r}", where=engine.name,
                       hint="give an espeak-ng language code (mpeg4fa voices lists them), or auto, en, zh")
    if not speaks_ipa(engine):
        raise TTSError(f"--lang {lang}: the {engine.name} engine gives no IPA phonemes, so it speaks only "
                       "auto, en and zh", where=engine.name, hint="use --engine espeak")
    known = getattr(engine, "languages", None)
    if known is not None and lang.lower() not in known():
        raise TTSError(f"unknown language {lang!r}", where=engine.name,
                       hint="run 'mpeg4fa voices' for the language codes espeak-ng speaks (or give auto, en, zh)")


def _route(kind: str, route: str) -> str:
    """How a run is turned into visemes: the English or the Mandarin table, or IPA features."""
    code = kind.lower()
    if code == "zh":
        return "zh"
    if (code == "en" or code.startswith("en-")) and route == "reference":
        return "en"
    return "ipa"


def _pinyin_text(text: str, start: int, end: int) -> tuple[str, dict[int, int], list[tuple[Syllable, int]]]:
    """The run as pinyin for espeak, a map text offset -> pinyin offset, and each syllable's offset."""
    sylls = {s.position: s for s in syllables(text[start:end])}
    parts: list[str] = []
    where: dict[int, int] = {}
    placed: list[tuple[Syllable, int]] = []
    length = 0
    for i in range(start, end):
        where[i] = length
        ch = text[i]
        if (i - start) in sylls:
            token = sylls[i - start].pinyin + " "
            placed.append((sylls[i - start], length))
        else:
            token = _PUNCT.get(ch, " " if ch.isspace() else "")
        parts.append(token)
        length += len(token)
    where[end] = length
    return "".join(parts), where, placed


def _split_final(s: Syllable, final_visemes: tuple[str, ...], phones: list[Event], start: float,
                 end: float) -> list[Timing]:
    """Time the final's glide / main vowel / ending inside [start, end]."""
    if len(phones) == len(final_visemes):
        return [Timing(p.text, v, p.start, p.end, "zh") for v, p in zip(final_visemes, phones)]
    roles = final_roles(s.final, len(final_visemes))
    weights = np.array([FINAL_WEIGHT[r] for r in roles])
    edges = start + (end - start) * np.r_[0.0, np.cumsum(weights) / weights.sum()]
    edges[-1] = end  # start + (end - start) can round an ulp past end, into the next phoneme
    return [Timing(f"{s.pinyin}:{role}", v, float(a), float(b), "zh")
            for v, role, a, b in zip(final_visemes, roles, edges[:-1], edges[1:])]


def _syllable_timings(s: Syllable, phones: list[Event]) -> list[Timing]:
    """A syllable's visemes timed by its phoneme events (pauses excluded)."""
    if not phones:
        return []
    start, end = phones[0].start, phones[-1].end
    if len(s.visemes) == 1:
        return [Timing(s.pinyin, s.visemes[0], start, end, "zh")]
    if s.initial and len(phones) >= 2:
        head = Timing(phones[0].text, s.visemes[0], phones[0].start, phones[0].end, "zh")
        return [head] + _split_final(s, s.visemes[1:], phones[1:], phones[1].start, end)
    return _split_final(s, s.visemes, phones, start, end)  # no initial, or one phoneme for both: share


def _mark_times(speech: Speech, marks: list[tuple[int, str]]) -> dict[str, float]:
    """When speech reached each mark; espeak drops a mark at a sentence start: take the next word's start."""
    times = {e.text: e.start for e in speech.marks()}
    words = sorted(speech.words(), key=lambda e: e.position)
    for offset, name in marks:
        if name not in times:
            later = [w.start for w in words if w.position >= offset]
            times[name] = later[0] if later else speech.duration
    return times


def _speak_zh(engine: Engine, text: str, start: int, end: int, marks: list[tuple[int, str]],
              rate: int | None) -> tuple[Speech, list[Timing], dict[str, float]]:
    pinyin, where, placed = _pinyin_text(text, start, end)
    local = [(min(where[min(max(o, start), end)], len(pinyin.strip())), name) for o, name in marks]
    speech = engine.synthesize(pinyin.strip() or ".", voice=PINYIN_VOICE, rate=rate, marks=local)
    words = sorted(speech.words(), key=lambda e: e.start)
    phonemes = [p for p in speech.phonemes()]
    by_position = {w.position: w for w in words}
    timings: list[Timing] = []
    found = []
    for syl, offset in placed:
        word = by_position.get(offset)
        if word is None:
            raise TTSError(f"the engine gave no timing for the syllable {syl.pinyin} ({syl.text})",
                           where=engine.name, hint="check the pinyin voice is installed")
        found.append((syl, word))
    if not _has_phonemes(speech):  # word boundaries only: estimate inside each syllable, resync at the next
        spu = seconds_per_unit(rate or getattr(engine, "rate", None), SYLLABLE_UNIT)
        placed_units = resync([w.start for _, w in found], [syllable_units(syl) for syl, _ in found],
                              speech.duration, spu)
        timings = [Timing(u.label, u.viseme, a, b, "zh") for u, a, b in placed_units]
        return speech, timings, _mark_times(speech, local)
    taken: set[int] = set()
    for syl, word in found:
        stop = words[words.index(word) + 1].start if words.index(word) + 1 < len(words) else speech.duration
        # a phoneme up to 20 ms before the word is its own, unless the syllable before has it: given to both,
        # its time was spoken twice and the second syllable started inside the first (spans overlap)
        mine = [k for k, p in enumerate(phonemes)
                if k not in taken and word.start - 0.02 <= p.start < stop and _voiced_phoneme(p.text)]
        taken.update(mine)
        timings += _syllable_timings(syl, [phonemes[k] for k in mine])
    timings += [Timing(p.text, PAUSE, p.start, p.end) for p in phonemes if p.text.startswith("_")]
    return speech, sorted(timings, key=lambda t: t.start), _mark_times(speech, local)


def _speak_en(engine: Engine, text: str, start: int, end: int, marks: list[tuple[int, str]],
              voice: str | None, rate: int | None) -> tuple[Speech, list[Timing], dict[str, float]]:
    chunk = text[start:end]
    lead = len(chunk) - len(chunk.lstrip())
    body = chunk.strip()
    local = [(min(max(o - start - lead, 0), len(body)), name) for o, name in marks]
    speech = engine.synthesize(body, voice=voice or ENGLISH_VOICE, rate=rate, marks=local)
    if not _has_phonemes(speech):
        timings = _english_by_words(speech, body, rate or getattr(engine, "rate", None))
    else:
        timings = [Timing(e.text, v, e.start, e.end) for v, e in english_visemes(list(speech.phonemes()))]
    return speech, timings, _mark_times(speech, local)


def _speak_ipa(engine: Engine, text: str, start: int, end: int, marks: list[tuple[int, str]],
               voice: str, rate: int | None) -> tuple[Speech, list[Timing], dict[str, float]]:
    """A run in any espeak-ng language: IPA phoneme events -> visemes by articulatory features."""
    chunk = text[start:end]
    lead = len(chunk) - len(chunk.lstrip())
    body = chunk.strip()
    local = [(min(max(o - start - lead, 0), len(body)), name) for o, name in marks]
    speech = engine.synthesize(body, voice=voice, rate=rate, marks=local, ipa=True)
    if not any(p.text.strip() for p in speech.phonemes()):
        raise TTSError(f"the {voice} voice gave no phonemes for {body[:40]!r}", where=engine.name,
                       hint="check the text is in a script that voice reads")
    placed = ipa_visemes(list(speech.phonemes()), where=f"{engine.name} {voice}",
                         is_sound=sounding(speech.samples, speech.rate))
    timings = [Timing(label, viseme, a, b) for label, viseme, a, b in placed]
    return speech, timings, _mark_times(speech, local)


def _voiced_phoneme(name: str) -> bool:
    """Whether a phoneme event of the pinyin voice is a sound: not a pause (``_``, ``_|``) nor a language
    switch (``(en)`` ... ``(cmn)``, around a syllable the voice spells out in English), which is no initial."""
    bare = name.strip()
    return not bare.startswith("_") and not (bare.startswith("(") and bare.endswith(")"))


def _has_phonemes(speech: Speech) -> bool:
    return any(not p.text.startswith("_") for p in speech.phonemes())


def _english_by_words(speech: Speech, body: str, rate: int | None) -> list[Timing]:
    """Visemes from each word's spelling, timed by estimate between the engine's word boundaries.

    A boundary covers its word and any following words the engine did not report on their own."""
    tokens = word_tokens(body)
    words = sorted(speech.words(), key=lambda e: e.start)
    first = snap_to_tokens([w.position for w in words], tokens)
    keep = [(w, k) for w, k in zip(words, first) if k >= 0]
    bounds = [k for _, k in keep[1:]] + [len(tokens)]
    units = [[u for tok in tokens[k:stop] for u in english_units(tok[2])] for (_, k), stop in zip(keep, bounds)]
    placed = resync([w.start for w, _ in keep], units, speech.duration, seconds_per_unit(rate))
    return [Timing(u.label, u.viseme, a, b) for u, a, b in placed]


def _join(parts: list[tuple[Speech, list[Timing], dict[str, float]]], engine_name: str,
          voice: str) -> tuple[Speech, list[Timing], dict[str, float]]:
    rate = parts[0][0].rate
    samples, events, timings, marks, offset = [], [], [], {}, 0.0
    for speech, times, mark_times in parts:
        if speech.rate != rate:
            raise TTSError(f"runs came back at {speech.rate} and {rate} Hz", where=engine_name)
        samples.append(speech.samples)
        events += [e.shifted(offset) for e in speech.events]
        timings += [t.shifted(offset) for t in times]
        marks.update({name: t + offset for name, t in mark_times.items()})
        offset += speech.duration
    joined = Speech(np.concatenate(samples), rate, tuple(sorted(events, key=lambda e: e.start)), engine_name, voice)
    return joined, timings, marks


def speak(markup: Markup, engine: Engine, *, lang: str = "auto", voice: str | None = None,
          rate: int | None = None, route: str = "reference") -> Utterance:
    """Speak the markup's text and time its visemes and tags (see the module docstring).

    ``lang``: ``auto`` (by script), ``en``, ``zh``, or any espeak-ng language code (engines with IPA
    phoneme events). ``voice``: under ``auto`` the voice of Latin (English) runs; with a language
    code, the voice for the whole text (default: the code itself). ``route="ipa"`` maps English
    through IPA features instead of ``spec/english_visemes.csv`` (to compare the two).
    """
    if route not in ROUTES:
        raise ValueError(f"route {route!r}: one of {', '.join(ROUTES)}")
    check_language(lang, engine)
    text = markup.text
    if not text.strip():
        raise MarkupError("there is nothing to say", 1, 1, hint="give some text", source=markup.name)
    languages = speaks_ipa(engine)
    # a script no voice here speaks: refused, not spoken as silence
    check_speakable(text, lang, markup.name, markup.place, languages=languages)
    pieces = runs(text, lang, languages)
    names = {i: f"tag{i}" for i in range(len(markup.tags))}
    parts, voices, ipa_runs = [], [], 0
    for n, (kind, start, end) in enumerate(pieces):
        last = n == len(pieces) - 1
        marks = [(tag.offset, names[i]) for i, tag in enumerate(markup.tags)
                 if (start <= tag.offset < end or (last and tag.offset >= end)) or (n == 0 and tag.offset < start)]
        how = _route(kind, route)
        if how == "zh":
            parts.append(_speak_zh(engine, text, start, end, marks, rate))
            voices.append(PINYIN_VOICE)
            continue
        if lang == "auto" or kind == "en":  # under auto, --voice is the voice of the English runs
            said = (voice or ENGLISH_VOICE) if kind == "en" else kind
        else:
            said = voice or kind
        voices.append(said)
        if how == "en":
            parts.append(_speak_en(engine, text, start, end, marks, said, rate))
            continue
        if not languages:
            raise TTSError(f"the {engine.name} engine gives no IPA phonemes", where=engine.name,
                           hint="use --engine espeak")
        ipa_runs += 1
        parts.append(_speak_ipa(engine, text, start, end, marks, said, rate))
    # the voices used; for English/Mandarin text under auto, en or zh, the English voice as before
    label = "+".join(dict.fromkeys(voices)) if ipa_runs or lang not in LANGS else (voice or ENGLISH_VOICE)
    speech, timings, times = _join(parts, engine.name, label)
    cues = tuple(ExpressionCue(tag.expression, tag.intensity, tag.seconds, times[names[i]])
                 for i, tag in enumerate(markup.tags))
    return Utterance(speech, tuple(timings), cues, markup)
