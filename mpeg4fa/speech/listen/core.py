"""A recording alone -> the :class:`~mpeg4fa.speech.utterance.Utterance` of a face saying it.

Three recognisers (``recognizer=``):

* ``words`` (English): the words pocketsphinx hears (:func:`.words.recognize_words`) become the
  transcript, aligned to the recording as a given transcript is (:func:`mpeg4fa.speech.align.align_recording`,
  pocketsphinx, the fit check off: the words came from the same model). If they cannot be aligned the
  block falls back to phones, and says so.
* ``phonetic`` (any language): the phones pocketsphinx's phone loop hears (:func:`.phones.recognize_phones`),
  read as IPA and mapped by their features (:mod:`mpeg4fa.speech.ipa`).
* ``either`` (English): both hear the block; the words path where the words explain the audio nearly as well
  as the free phone loop does (:func:`word_confidence` at least :data:`WORDS_CONFIDENT`: speech like a
  person's, which the word recogniser was trained on), else the phones path (a synthetic voice such as
  espeak-ng's, whose words it misreads and whose closures the detector learned). Other languages: phonetic.
  A recording heard block by block (:mod:`.stream`) is one kind of voice: its first pair of blocks, judged
  together, settles the recogniser of the rest (:func:`settled`), so both decoders run on the first blocks only.

``auto`` takes :data:`ENGLISH_DEFAULT` for English (``lang`` ``en``, ``en-*`` or ``auto``: with no text there
is no script to tell the language by) and ``phonetic`` for every other language.

Both are gated by voice activity (:func:`.voice.voice_activity`): silence, breath, noise and music give a
closed mouth at rest, never chatter. The utterance plays the recording's own audio; expressions come only from
``expression`` (one cue for the whole clip), since there is no text to tag.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from mpeg4fa.speech.align.recording import HOP, Recording
from mpeg4fa.speech.listen.compare import CLOSURE
from mpeg4fa.speech.listen.closures import refined_phones
from mpeg4fa.speech.listen.phones import (Phone, phone_decoder, phone_events, phone_timings, recognize_phones,
                                          speech_share)
from mpeg4fa.speech.listen.voice import voice_activity
from mpeg4fa.speech.listen.words import HeardWord, recognize_words, word_decoder
from mpeg4fa.speech.markup import Markup
from mpeg4fa.speech.timeline import ExpressionCue
from mpeg4fa.speech.tts.base import Event, Speech
from mpeg4fa.speech.utterance import Timing, Utterance
from mpeg4fa.speech.visemes import PAUSE

RECOGNIZERS = ("auto", "words", "phonetic", "either")
ENGLISH_DEFAULT = "either"
"""What ``auto`` uses for English: the one that found the most closures within 40 ms over espeak-ng's speech, the
LibriVox recordings (tools/bench_lipsync_audio.py --human) and festival's voices (tools/bench_lipsync_festival.py),
2026-12-07, each utterance decoded from a fresh front end: either 92.2 / 82.8 / 72.8, 68.4, 54.4 % (phonetic 92.2 /
55.2 / 52.2, 71.3, 58.1; words 35.2 / 82.8 / 72.1, 68.4, 61.0); speed on 2 cores (tools/bench_lipsync_audio.json,
2026-12-07, a machine 1.4x slower than the day before): espeak-ng 10.1-13.7x real time from 5 to 60 s, people's
speech (LibriVox) 10.3-11.5x (phonetic 23-39x)."""
WORDS_CONFIDENT = -23.0
"""``either`` takes the words path where :func:`word_confidence` is at least this (pocketsphinx's log units,
base 1.0001, per 10 ms of words). Measured 2026-12-06 per sentence (tools/bench_lipsync_audio.py's English
texts): espeak-ng's voices -72 to -27.1, festival's HTS voice slt -19.1 to -12.0, the LibriVox recordings
-19.5 to -15.8 (festival's diphone voices kal -28.5 to -18.6, ked -30.7 to -20.0, between): the middle of
the gap between espeak-ng's and the natural speech's. Chosen on those same sentences (no held-out set);
closures within 40 ms were alike from -27 to -20."""
EXPRESSION_SECONDS = 0.5
"""How long the whole-clip expression takes to come in."""
ENGINE = "recording"


def is_english(lang: str) -> bool:
    """Whether ``lang`` is English for the recogniser (``auto`` is: no text to tell otherwise; ``--voice``
    goes only with a transcript, so the language is ``--lang``'s)."""
    code = (lang or "auto").lower()
    return code in ("auto", "en") or code.startswith("en-")


def check_language(recognizer: str, lang: str) -> None:
    """AlignError for the ``words`` recogniser with a language other than English: its dictionary and
    language model are English, so it would hear English words in any speech (and the mouth would say
    them); ``phonetic`` hears the phones of any language."""
    if recognizer == "words" and not is_english(lang):
        from mpeg4fa.speech.align.errors import AlignError

        raise AlignError(f"the words recogniser knows only English, not {lang!r}", where="--recognizer words",
                         hint="use --recognizer phonetic, which hears the phones of any language, or give what "
                              "is said with --transcript")


def choose_recognizer(recognizer: str, lang: str) -> str:
    """The recogniser ``auto`` stands for (see the module docstring); ValueError for an unknown one."""
    if recognizer not in RECOGNIZERS:
        raise ValueError(f"recognizer {recognizer!r}: one of {', '.join(RECOGNIZERS)}")
    if recognizer == "auto":
        return ENGLISH_DEFAULT if is_english(lang) else "phonetic"
    if recognizer == "either" and not is_english(lang):
        return "phonetic"
    return recognizer


@dataclass(frozen=True)
class Listened:
    """What :func:`listen` made of a recording: the utterance on it, the recogniser used (``either``: the one it
    took), the words heard (``words`` only), seconds of voice activity, a note when a block fell back to phones,
    and ``either``'s :func:`word_confidence` (NaN for the others)."""

    utterance: Utterance
    recognizer: str
    words: tuple[HeardWord, ...] = ()
    voiced: float = 0.0
    notes: tuple[str, ...] = field(default=())
    confidence: float = float("nan")

    @property
    def silent(self) -> bool:
        """No speech found: the mouth stays closed throughout."""
        return all(t.viseme == PAUSE for t in self.utterance.timings)


def expression_cues(expression: tuple[str, int] | None) -> tuple[ExpressionCue, ...]:
    """``(name, intensity)`` -> one cue from the start of the clip (or none)."""
    if expression is None:
        return ()
    name, intensity = expression
    return (ExpressionCue(name, int(intensity), EXPRESSION_SECONDS, 0.0),)


def _gated(timings: list[Timing], active: np.ndarray) -> list[Timing]:
    """Timings mostly outside voice activity shown as a pause (a closure's silence counts as speech before
    its release: :func:`~.phones.speech_share`)."""
    return [t if t.viseme == PAUSE or speech_share(t.start, t.end, active, closure=t.viseme == CLOSURE) >= 0.5 else
            Timing(t.phoneme, PAUSE, t.start, t.end, t.set) for t in timings]


def _phonetic(rec: Recording, active: np.ndarray, loop: list[Phone] | None = None) -> tuple[list[Timing], list[Event]]:
    """The phones path; ``loop``: the phone loop's phones already heard (closures not yet placed)."""
    events = phone_events(recognize_phones(rec) if loop is None else refined_phones(rec, loop), active)
    return phone_timings(events), events


def word_confidence(words: tuple[float, int], loop: tuple[float, int]) -> float:
    """How well the words heard explain the audio: the word decoder's acoustic log-likelihood minus the free
    phone loop's (:func:`~mpeg4fa.speech.align.sphinx.acoustic_score` of each over the same audio), per 10 ms
    of words. Near 0 when the words say what the phones do; far below on speech the word recogniser's language
    model has to bend into words (espeak-ng's voices)."""
    return (words[0] - loop[0]) / max(words[1], 1)


def _words(rec: Recording, active: np.ndarray, lang: str, heard: list[HeardWord] | None = None,
           loop: list[Phone] | None = None) -> tuple[list[Timing], list[Event], list[HeardWord], str]:
    """The words path (``heard``: the words already recognised); on an alignment failure the phones path (on
    ``loop``, the phone loop's phones, when already heard), with the reason."""
    from mpeg4fa.speech.align import AlignError, align_recording

    heard = recognize_words(rec, active=active) if heard is None else heard
    if not heard:
        return [], [], [], ""
    text = " ".join(w.word for w in heard)
    try:
        aligned = align_recording(rec, text, lang=lang if lang.lower().startswith("en") else "en",
                                  method="pocketsphinx", fit_check=False, measure_fit=False,
                                  name="<recognised words>")
    except AlignError as exc:
        timings, events = _phonetic(rec, active, loop)
        return timings, events, heard, f"the words heard could not be aligned ({exc.message}); phones used"
    utt = aligned.utterance
    events = [e for e in utt.speech.events if e.kind in ("phoneme", "word")]
    return list(utt.timings), events, heard, ""


PhoneLoop = tuple[list[Phone], tuple[float, int]]
"""What the free phone loop heard in a block: its phones (closures not yet placed) and its
:func:`~mpeg4fa.speech.align.sphinx.acoustic_score`."""


def phone_loop(rec: Recording) -> PhoneLoop:
    """``either``'s phone-loop pass over ``rec`` (:data:`PhoneLoop`); a function of its own so that another
    process can run it while this one decodes the words (:func:`.stream.heard_blocks`)."""
    from mpeg4fa.speech.align.sphinx import acoustic_score

    return recognize_phones(rec, closures=False), acoustic_score(phone_decoder())


def _either(rec: Recording, active: np.ndarray, lang: str, loop: Callable[[], PhoneLoop] | None = None,
            ) -> tuple[list[Timing], list[Event], list[HeardWord], str, str, float]:
    """``either`` (module docstring): the phone loop and the word decoder on the block, then the words path
    (its alignment) or the phones path (the closure detector) by :func:`word_confidence`; each pass once.
    ``loop``: the phone loop's pass started elsewhere (a helper process), called for its result once the words
    are decoded here; the two decoders are independent, so the result is the one of both run here."""
    from mpeg4fa.speech.align.sphinx import acoustic_score

    here = phone_loop(rec) if loop is None else None
    heard = recognize_words(rec, active=active)
    words_score = acoustic_score(word_decoder()) if heard else None
    phones, loop_score = loop() if here is None else here
    confidence = word_confidence(words_score, loop_score) if words_score is not None else float("-inf")
    if confidence >= WORDS_CONFIDENT:
        timings, events, heard, note = _words(rec, active, lang, heard, phones)
        if not note:
            return timings, events, heard, "", "words", confidence
        return timings, events, heard, note, "phonetic", confidence
    timings, events = _phonetic(rec, active, phones)
    return timings, events, [], "", "phonetic", confidence


def settled(how: str, *heard: Listened) -> str:
    """The recogniser for the rest of a recording once ``either`` has judged the words of its first blocks
    (``heard``, judged together: their confidences weighed by their seconds of voice). A recording is one kind of
    voice, so one recogniser serves all of it, and later blocks need not run both decoders."""
    judged = [(h.confidence, h.voiced) for h in heard if np.isfinite(h.confidence)]
    if how != "either" or not judged:
        return how
    confidence, voiced = np.array(judged).T  # a judgement without voice seconds (made by hand) counts alike
    mean = float(np.average(confidence, weights=voiced)) if voiced.sum() > 0 else float(confidence.mean())
    return "words" if mean >= WORDS_CONFIDENT else "phonetic"


def listen(recording: Recording, *, recognizer: str = "auto", lang: str = "auto",
           expression: tuple[str, int] | None = None, active: np.ndarray | None = None,
           loop: Callable[[], PhoneLoop] | None = None) -> Listened:
    """The face's utterance for ``recording`` (see the module docstring): visemes timed on it, its audio,
    ``expression`` (name, intensity 0-63) for the whole clip. ``active``: its voice activity per 10 ms
    frame, when already known (:func:`~.voice.voice_activity`). ``loop``: ``either``'s phone-loop pass, started
    elsewhere (:func:`_either`)."""
    how = choose_recognizer(recognizer, lang)
    check_language(how, lang)
    if active is None:
        active = voice_activity(recording.floats(), recording.rate)
    heard: list[HeardWord] = []
    notes: list[str] = []
    confidence = float("nan")
    if not active.any():
        timings, events = [], []
    elif how == "either":
        timings, events, heard, note, how, confidence = _either(recording, active, lang, loop)
        notes += [note] if note else []
    elif how == "words":
        timings, events, heard, note = _words(recording, active, lang)
        notes += [note] if note else []
    else:
        timings, events = _phonetic(recording, active)
    timings = _gated(timings, active)
    markup = Markup(" ".join(w.word for w in heard), ())
    speech = Speech(recording.samples, recording.rate, tuple(sorted(events, key=lambda e: e.start)), ENGINE,
                    f"recognised:{how}")
    utterance = Utterance(speech, tuple(timings), expression_cues(expression), markup)
    return Listened(utterance, how, tuple(heard), float(active.sum() * HOP), tuple(notes), confidence)
