"""A recording alone -> the :class:`~mpeg4fa.speech.utterance.Utterance` of a face saying it.

Two recognisers (``recognizer=``):

* ``words`` (English): the words pocketsphinx hears (:func:`.words.recognize_words`) become the
  transcript, aligned to the recording as a given transcript is (:func:`mpeg4fa.speech.align.align_recording`,
  pocketsphinx, the fit check off: the words came from the same model). If they cannot be aligned the
  block falls back to phones, and says so.
* ``phonetic`` (any language): the phones pocketsphinx's phone loop hears (:func:`.phones.recognize_phones`),
  read as IPA and mapped by their features (:mod:`mpeg4fa.speech.ipa`).

``auto`` takes :data:`ENGLISH_DEFAULT` for English (``lang`` ``en``, ``en-*`` or ``auto``: with no text there
is no script to tell the language by) and ``phonetic`` for every other language.

Both are gated by voice activity (:func:`.voice.voice_activity`): silence, breath, noise and music give a
closed mouth at rest, never chatter. The utterance plays the recording's own audio; expressions come only from
``expression`` (one cue for the whole clip), since there is no text to tag.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mpeg4fa.speech.align.recording import HOP, Recording
from mpeg4fa.speech.listen.compare import CLOSURE
from mpeg4fa.speech.listen.phones import phone_events, phone_timings, recognize_phones, speech_share
from mpeg4fa.speech.listen.voice import voice_activity
from mpeg4fa.speech.listen.words import HeardWord, recognize_words
from mpeg4fa.speech.markup import Markup
from mpeg4fa.speech.timeline import ExpressionCue
from mpeg4fa.speech.tts.base import Event, Speech
from mpeg4fa.speech.utterance import Timing, Utterance
from mpeg4fa.speech.visemes import PAUSE

RECOGNIZERS = ("auto", "words", "phonetic")
ENGLISH_DEFAULT = "phonetic"
"""What ``auto`` uses for English: the one that matched the transcript path better in
tools/bench_lipsync_audio.py (closure onsets and frame agreement on English speech)."""
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
    return recognizer


@dataclass(frozen=True)
class Listened:
    """What :func:`listen` made of a recording: the utterance on it, the recogniser used, the words heard
    (``words`` only), seconds of voice activity, and a note when a block fell back to phones."""

    utterance: Utterance
    recognizer: str
    words: tuple[HeardWord, ...] = ()
    voiced: float = 0.0
    notes: tuple[str, ...] = field(default=())

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


def _phonetic(rec: Recording, active: np.ndarray) -> tuple[list[Timing], list[Event]]:
    events = phone_events(recognize_phones(rec), active)
    return phone_timings(events), events


def _words(rec: Recording, active: np.ndarray, lang: str) -> tuple[list[Timing], list[Event], list[HeardWord], str]:
    """The words path; on an alignment failure the phones path, with the reason."""
    from mpeg4fa.speech.align import AlignError, align_recording

    heard = recognize_words(rec, active=active)
    if not heard:
        return [], [], [], ""
    text = " ".join(w.word for w in heard)
    try:
        aligned = align_recording(rec, text, lang=lang if lang.lower().startswith("en") else "en",
                                  method="pocketsphinx", fit_check=False, name="<recognised words>")
    except AlignError as exc:
        timings, events = _phonetic(rec, active)
        return timings, events, heard, f"the words heard could not be aligned ({exc.message}); phones used"
    utt = aligned.utterance
    events = [e for e in utt.speech.events if e.kind in ("phoneme", "word")]
    return list(utt.timings), events, heard, ""


def listen(recording: Recording, *, recognizer: str = "auto", lang: str = "auto",
           expression: tuple[str, int] | None = None, active: np.ndarray | None = None) -> Listened:
    """The face's utterance for ``recording`` (see the module docstring): visemes timed on it, its audio,
    ``expression`` (name, intensity 0-63) for the whole clip. ``active``: its voice activity per 10 ms
    frame, when already known (:func:`~.voice.voice_activity`)."""
    how = choose_recognizer(recognizer, lang)
    check_language(how, lang)
    if active is None:
        active = voice_activity(recording.floats(), recording.rate)
    heard: list[HeardWord] = []
    notes: list[str] = []
    if not active.any():
        timings, events = [], []
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
    return Listened(utterance, how, tuple(heard), float(active.sum() * HOP), tuple(notes))
