"""A recording and its transcript -> the same :class:`~mpeg4fa.speech.utterance.Utterance` the TTS path
makes, timed on the recording and playing its audio.

The transcript (expression tags allowed) is spoken by espeak-ng exactly as :func:`~mpeg4fa.speech.
utterance.speak` does for text: that gives the phones, their visemes (the English, Mandarin or IPA
tables, unchanged) and a reference timing. The aligner then finds a monotone map from the reference's
time to the recording's, and every phoneme, viseme, word, mark and expression cue goes through it:

* ``pocketsphinx`` (English): forced alignment of the transcript's words and their phones. Each word's
  start and end is an anchor; inside a word whose phone count matches espeak's, every phone onset is
  one too, else the onsets of the phones that pair by name (espeak's in ARPAbet, in order); espeak's
  other phones share what is left in proportion to their own durations. A stop is never an anchor:
  pocketsphinx starts it at the closure, espeak-ng at the release (the encoder then moves the viseme
  back over the closure, :mod:`mpeg4fa.speech.closures`). pocketsphinx's frame times are moved to the
  middle between frame centres (:data:`.sphinx.OFFSET`).
* ``dtw`` (any language): dynamic time warping between the recording and the reference on normalised
  cepstra, with the recording's frequency axis scaled to the reference voice's (:mod:`.dtw`); the reference is first re-spoken at the rate that gives it the recording's
  length of speech, so the warp corrects what a straight line cannot.

``auto`` takes pocketsphinx for English transcripts of letter words (a word the CMU dictionary lacks is
added, pronounced as espeak-ng says it), DTW for the rest.

Either aligner finds some path for a transcript of about the right length, so the length and coverage
checks pass other words too. pocketsphinx mostly finds none for them (its beam loses the path: "no path");
where it does, the fit check refuses them (:func:`check_fit`): the forced alignment's acoustic score
against a free phone decoding's, per frame, right transcripts -3 to -28, wrong ones -51 and below
(tools/bench_align.py). DTW's mean path cost is reported but not judged: on human speech the right
transcript's overlaps a wrong one's, against any baseline tried.
"""
from __future__ import annotations

import difflib
import os
import time
from dataclasses import dataclass, replace

import numpy as np

from mpeg4fa.speech.align.errors import AlignError
from mpeg4fa.speech.align.recording import HOP, Recording, check_speech, read_recording, resample
from mpeg4fa.speech.markup import Markup, parse_markup
from mpeg4fa.speech.script import runs
from mpeg4fa.speech.tts.base import Event, Speech, snap_to_tokens, word_tokens
from mpeg4fa.speech.utterance import Timing, Utterance, check_language, speak
from mpeg4fa.speech.visemes import PAUSE

METHODS = ("auto", "pocketsphinx", "dtw")
FIT_RATIO = 3.0
"""The recording's speech may last at most this many times the transcript's spoken length, or a third of it."""
MIN_COVERAGE = 0.8
"""Share of the recording's speech frames the aligned transcript must span."""
_ASCII_WORD = set("abcdefghijklmnopqrstuvwxyz'")


@dataclass(frozen=True)
class Alignment:
    """What :func:`align_recording` found: the utterance on the recording, the reference it came from,
    the aligner used, the anchors of the time map (reference s -> recording s), the share of the
    recording's speech the aligned phones span, and the seconds the alignment took."""

    utterance: Utterance
    reference: Utterance
    method: str
    anchors: tuple[np.ndarray, np.ndarray]
    coverage: float
    seconds: float
    fit: float = float("nan")
    """How well the transcript fits the recording (:data:`FIT_LIMITS`): pocketsphinx's per-frame
    log-likelihood ratio of the forced alignment to a free phone decoding, or DTW's mean distance
    along the path."""

    def warp(self, t):
        """Reference time(s) -> recording time(s)."""
        return np.interp(t, *self.anchors)


def _sounding(timings) -> list[Timing]:
    return [t for t in timings if t.viseme != PAUSE and t.end > t.start]


def _speech_seconds(utt: Utterance) -> tuple[float, float, float]:
    """(first sound start, last sound end, seconds of phones) of a spoken utterance."""
    sound = _sounding(utt.timings)
    if not sound:
        return 0.0, 0.0, 0.0
    return sound[0].start, max(t.end for t in sound), sum(t.end - t.start for t in sound)


def is_english(text: str, lang: str) -> bool:
    """Whether the transcript is all English (what pocketsphinx's model speaks)."""
    code = lang.lower()
    if code == "en" or code.startswith("en-"):
        return True
    if code != "auto":
        return False
    return all(kind == "en" for kind, _, _ in runs(text, "auto", True))


def _dictionary_words(text: str) -> list[str] | None:
    """The transcript's words for pocketsphinx, or None if one is not plain ASCII letters."""
    words = [w.lower() for _, _, w in word_tokens(text)]
    return words if words and all(set(w) <= _ASCII_WORD for w in words) else None


def choose_method(method: str, text: str, lang: str) -> str:
    if method not in METHODS:
        raise ValueError(f"method {method!r}: one of {', '.join(METHODS)}")
    english = is_english(text, lang)
    if method == "pocketsphinx":
        if not english:
            raise AlignError(f"pocketsphinx aligns English only, not --lang {lang}", where="pocketsphinx",
                             hint="use the dtw aligner for other languages")
        words = _dictionary_words(text)
        if words is None:
            raise AlignError("pocketsphinx aligns words of letters only (no digits or other scripts)",
                             where="pocketsphinx", hint="spell numbers out, or use the dtw aligner")
        return method
    if method == "dtw" or not english or _dictionary_words(text) is None:
        return "dtw"
    from mpeg4fa.extras import absent

    return "dtw" if absent("align", "pocketsphinx") else "pocketsphinx"  # DTW where the align extra is not installed


def _word_phonemes(ref: Utterance) -> list[list[str] | None]:
    """Per word of the transcript, espeak-ng's phonemes for it (None where espeak read it with its
    neighbours as one word, or gave it none)."""
    tokens = word_tokens(ref.markup.text)
    phones = [e for e in ref.speech.phonemes() if not e.text.startswith("_")]
    words = sorted(ref.speech.words(), key=lambda e: e.start)
    keep = [(w, k) for w, k in zip(words, snap_to_tokens([w.position for w in words], tokens)) if k >= 0]
    out: list[list[str] | None] = [None] * len(tokens)
    for n, (w, k) in enumerate(keep):
        stop_k = keep[n + 1][1] if n + 1 < len(keep) else len(tokens)
        stop_t = keep[n + 1][0].start if n + 1 < len(keep) else ref.speech.duration
        mine = [p.text for p in phones if w.start - 0.02 <= p.start < stop_t - 0.005]
        if stop_k == k + 1 and mine:
            out[k] = mine
    return out


def _learn_words(ref: Utterance, explicit: bool) -> bool:
    """Add the transcript's words the CMU dictionary lacks, pronounced as espeak-ng said them; False
    (or, when pocketsphinx was asked for, AlignError) if one cannot be."""
    from mpeg4fa.speech.align.sphinx import add_words, arpabet, unknown_words

    words = _dictionary_words(ref.markup.text) or []
    unknown = set(unknown_words(words))
    if not unknown:
        return True
    said = _word_phonemes(ref)
    learned, failed = {}, []
    for word, phonemes in zip(words, said):
        if word in unknown and word not in learned:
            pron = arpabet(phonemes) if phonemes else None
            if pron is None:
                failed.append(word)
            else:
                learned[word] = pron
    if failed:
        if explicit:
            raise AlignError(f"not in pocketsphinx's dictionary and not spelt out by espeak-ng alone: "
                             f"{', '.join(sorted(set(failed)))}", where="pocketsphinx", hint="use the dtw aligner")
        return False
    add_words(learned)
    return True


def _monotone(ref: np.ndarray, rec: np.ndarray, ref_end: float, rec_end: float) -> tuple[np.ndarray, np.ndarray]:
    """Anchors sorted, with (0, 0) and the two ends, recording times never going back."""
    ref = np.r_[0.0, np.asarray(ref, dtype=np.float64), ref_end]
    rec = np.r_[0.0, np.clip(np.asarray(rec, dtype=np.float64), 0.0, rec_end), rec_end]
    keep = (ref >= 0) & (ref <= ref_end)
    ref, rec = ref[keep], rec[keep]
    order = np.argsort(ref, kind="stable")
    ref, rec = ref[order], np.maximum.accumulate(rec[order])
    uniq, inverse = np.unique(ref, return_inverse=True)
    out = np.bincount(inverse, weights=rec) / np.bincount(inverse)
    return uniq, np.maximum.accumulate(out)


def _sphinx_anchors(rec: Recording, ref: Utterance, fit: bool = True) -> tuple[np.ndarray, np.ndarray, float]:
    from mpeg4fa.speech.align.sphinx import ESPEAK_ARPABET, STOPS, align_words

    text = ref.markup.text
    tokens = word_tokens(text)
    aligned, fit = align_words(rec, [w.lower() for _, _, w in tokens], fit=fit)
    phones = [e for e in ref.speech.phonemes() if not e.text.startswith("_")]
    words = sorted(ref.speech.words(), key=lambda e: e.start)
    first = snap_to_tokens([w.position for w in words], tokens)
    keep = [(w, k) for w, k in zip(words, first) if k >= 0]
    ref_t, rec_t = [], []
    for n, (w, k) in enumerate(keep):
        stop_k = keep[n + 1][1] if n + 1 < len(keep) else len(tokens)
        stop_t = keep[n + 1][0].start if n + 1 < len(keep) else ref.speech.duration
        if stop_k <= k:
            continue
        mine = [p for p in phones if w.start - 0.02 <= p.start < stop_t - 0.005]
        theirs = [p for a in aligned[k:stop_k] for p in a.phones]
        if not mine or not theirs:
            continue
        if len(mine) == len(theirs):  # one for one: every onset but a stop's is an anchor
            pairs = [(p.start, q[1]) for p, q in zip(mine, theirs) if q[0] not in STOPS]
        else:  # the word's start (unless a stop's closure), and the phones that pair by ARPAbet name
            pairs = [(mine[0].start, aligned[k].start)] if theirs[0][0] not in STOPS else []
            names = [(ESPEAK_ARPABET.get(p.text) or "?").split()[0] for p in mine]
            match = difflib.SequenceMatcher(None, names, [q[0] for q in theirs], autojunk=False)
            pairs += [(mine[b.a + i].start, theirs[b.b + i][1]) for b in match.get_matching_blocks()
                      for i in range(b.size) if theirs[b.b + i][0] not in STOPS and b.a + i > 0]
        ref_t += [a for a, _ in pairs]
        rec_t += [b for _, b in pairs]
        after = aligned[stop_k].phones[:1] if stop_k < len(aligned) else ()
        if not after or after[0][0] not in STOPS:  # a word's end, unless it is the next stop's closure
            ref_t.append(mine[-1].end)
            rec_t.append(aligned[stop_k - 1].end)
    return np.array(ref_t), np.array(rec_t), fit


def _dtw_anchors(rec: Recording, ref: Utterance) -> tuple[np.ndarray, np.ndarray, float]:
    from mpeg4fa.speech.align import dtw

    path, _, cost = dtw.align(resample(ref.speech.samples.astype(np.float64) / 32768.0, ref.speech.rate, dtw.RATE),
                              resample(rec.floats(), rec.rate, dtw.RATE))
    return (*dtw.warp_anchors(path), cost)


def _warped(ref: Utterance, rec: Recording, anchors, engine: str) -> Utterance:
    f = lambda t: float(np.interp(t, *anchors))  # noqa: E731
    events = sorted((Event(e.kind, f(e.start), max(f(e.end), f(e.start)), e.text, e.position)
                     for e in ref.speech.events), key=lambda e: e.start)
    speech = Speech(rec.samples, rec.rate, tuple(events), engine, ref.speech.voice)
    timings = tuple(Timing(t.phoneme, t.viseme, f(t.start), max(f(t.end), f(t.start)), t.set) for t in ref.timings)
    cues = tuple(replace(c, start=f(c.start)) for c in ref.cues)
    return Utterance(speech, timings, cues, ref.markup)


def _no_fit(rec: Recording, why: str) -> AlignError:
    return AlignError(f"the transcript does not fit the recording: {why}", where=rec.name,
                      hint="check the transcript is what the recording says (and --lang its language)")


FIT_LIMITS = {"pocketsphinx": -40.0, "dtw": None}
"""The worst fit score each aligner accepts (None: no check; see :func:`check_fit`)."""


def check_fit(method: str, fit: float, rec: Recording, name: str) -> None:
    """Raise :class:`AlignError` if the transcript's words are not what the recording says: the
    aligners always find some path, so a wrong transcript of about the right length passes the
    length and coverage checks; its acoustic fit does not (figures: tools/bench_align.py)."""
    limit = FIT_LIMITS.get(method)
    if limit is None or fit >= limit:
        return
    raise AlignError(f"the transcript does not fit the recording: {method}'s fit score {fit:.1f} is below "
                     f"{limit:.1f} (the words aligned are not what is said)", where=f"{rec.name} / {name}",
                     hint="check that the transcript is what is said in the recording; --no-fit-check to "
                          "align anyway")


def _check_runs(markup: Markup, name: str) -> None:
    """MarkupError at the first run without a space longer than a word can be (:data:`~mpeg4fa.speech.chunks.MAX_RUN`):
    the transcript is spoken whole as the reference, and espeak-ng is never handed such a run (text spoken
    without a recording is cut there instead; a transcript must be the words said)."""
    from mpeg4fa.speech.chunks import MAX_RUN, long_run
    from mpeg4fa.speech.errors import MarkupError

    run = long_run(markup.text)
    if run is not None:
        line, column = markup.place(run.start())
        raise MarkupError(f"{len(run.group()):,} characters without a space: longer than any word ({MAX_RUN} at most)",
                          line, column, "a transcript is the words the recording says: put spaces between them",
                          name)


def align_recording(recording: Recording | str | os.PathLike, transcript: str | Markup, *, lang: str = "auto",
                    voice: str | None = None, rate: int | None = None, method: str = "auto",
                    name: str = "<transcript>", fit_check: bool = True, measure_fit: bool = True) -> Alignment:
    """Time ``transcript`` (tagged text or a parsed :class:`Markup`) on ``recording`` (a WAV path or a
    :class:`Recording`); see the module docstring. ``voice``/``rate``: espeak-ng's reference (default
    the language's voice at 175 wpm; DTW picks its own rate unless ``rate`` is given). ``fit_check``:
    refuse a transcript whose words are not what the recording says (:func:`check_fit`). ``measure_fit`` off
    (and ``fit_check`` off): no fit measured (``Alignment.fit`` NaN), a quarter less time for pocketsphinx.

    Raises :class:`AlignError` for a missing, unreadable or silent recording and a transcript that
    does not fit it, :class:`~mpeg4fa.speech.errors.TTSError` for an unknown language,
    :class:`~mpeg4fa.speech.errors.MarkupError` for bad tags.
    """
    from mpeg4fa.speech.tts.espeak import DEFAULT_RATE, RATE_RANGE, EspeakEngine

    began = time.perf_counter()
    rec = recording if isinstance(recording, Recording) else read_recording(recording)
    markup = transcript if isinstance(transcript, Markup) else parse_markup(transcript, name=name)
    _check_runs(markup, name)
    engine = EspeakEngine()
    check_language(lang, engine)
    how = choose_method(method, markup.text, lang)
    frames = check_speech(rec)
    rec_speech = float(np.flatnonzero(frames)[-1] - np.flatnonzero(frames)[0] + 1) * HOP
    ref = speak(markup, engine, lang=lang, voice=voice, rate=rate)
    if how == "pocketsphinx" and not _learn_words(ref, explicit=method == "pocketsphinx"):
        how = "dtw"
    start, end, _ = _speech_seconds(ref)
    ratio = rec_speech / max(end - start, 1e-3)
    if not 1 / FIT_RATIO <= ratio <= FIT_RATIO:
        raise _no_fit(rec, f"it holds {rec_speech:.2f} s of speech where the transcript takes "
                           f"{end - start:.2f} s to say")
    if how == "dtw" and rate is None:  # a reference as long as the recording: the warp corrects the rest
        wpm = int(np.clip(round(DEFAULT_RATE / ratio), *RATE_RANGE))
        if abs(wpm - DEFAULT_RATE) > 5:
            ref = speak(markup, engine, lang=lang, voice=voice, rate=wpm)
    *anchors, fit = (_sphinx_anchors(rec, ref, fit=measure_fit or fit_check) if how == "pocketsphinx" else
                     _dtw_anchors(rec, ref))
    if fit_check:
        check_fit(how, fit, rec, name)
    anchors = _monotone(*anchors, ref.speech.duration, rec.duration)
    utterance = _warped(ref, rec, anchors, "recording")
    start, end, _ = _speech_seconds(utterance)
    lo, hi = np.flatnonzero(frames)[[0, -1]] * HOP
    inside = frames[int(start / HOP):int(np.ceil(end / HOP)) + 1].sum() / max(frames.sum(), 1)
    if inside < MIN_COVERAGE:
        raise _no_fit(rec, f"the aligned transcript spans {100 * inside:.0f} % of the recording's speech "
                           f"({lo:.2f}-{hi:.2f} s)")
    return Alignment(utterance, ref, how, anchors, float(inside), time.perf_counter() - began, float(fit))
