"""Tagged text -> FAP frames: the encoder's last step before the bitstream.

The spoken text's timings are first corrected where the engine's events and
the sound part ways (stops start at their closure's silence, :mod:`.closures`);
the timeline (:mod:`.timeline`) then gives low-level FAPs for every frame; the
stream carries them at the chosen level:

* ``high``: FAP 1 (two visemes and their blend) and FAP 2 (two expressions and
  intensities), a few bits a frame. FAP 1 can only name the 14 MPEG-4 visemes
  and FAP 2 the 6 MPEG-4 expressions: Chinese visemes and further expressions go
  out as low-level FAPs in the frames that need them (their merged values, since a
  sent low-level FAP overrides the high-level one at the decoder);
* ``low``: FAPs 3-68, the merged curves (visemes, expressions, idle motion);
* ``both``: the high-level fields plus the low-level FAPs.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, replace
from functools import partial

import numpy as np

from mpeg4fa.decoded import ClampWarning, resolve
from mpeg4fa.fba import EncodeOptions
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.fba.syntax import MASK_ALL, MASK_HOLD, MASK_INTERPOLATE, MASK_NONE
from mpeg4fa.spec import EXPRESSIONS, FAP_GROUP, FAP_GROUP_SLICES, FAP_PARTNERS, FULL_INTENSITY, VISEMES
from mpeg4fa.speech.closures import stop_closures
from mpeg4fa.speech.compact import compact_expressions, compact_visemes, plan_expression_mask
from mpeg4fa.speech.markup import parse_markup
from mpeg4fa.speech.timeline import (CLOSURE_HOLD, expression_fields, expression_track, frame_times, idle_track,
                                     merge_tracks, viseme_fields, viseme_track)
from mpeg4fa.speech.tts.base import Engine
from mpeg4fa.speech.utterance import Utterance, speak

LEVELS = ("high", "low", "both")
TEXT_CODING = {"optimize": True, "fap_quant": 3}
"""Coding options for streams made from text (tools/bench_encoder.py measures what they save)."""
_VISEME_CODE = {v.name: v.number for v in VISEMES}
_EXPRESSION_CODE = {e.name: e.number for e in EXPRESSIONS}


@dataclass(frozen=True)
class Encoded:
    """What the encoder made: the FAP stream, the speech it goes with, and the timeline behind it.

    The stream carries how a decoder must read the FAPs it leaves out
    (:attr:`~mpeg4fa.fba.stream.FapStream.mask_types`), so it keeps its meaning under any
    :class:`~mpeg4fa.fba.EncodeOptions`; :meth:`coding` gives the ones streams from text use.
    """

    stream: FapStream
    utterance: Utterance
    values: np.ndarray  # (n, 68) merged low-level FAP values the stream stands for
    level: str

    def coding(self, **overrides) -> EncodeOptions:
        """The options to encode :attr:`stream` with: ``TEXT_CODING``, then ``overrides``."""
        return EncodeOptions(**{**TEXT_CODING, **overrides})

    @property
    def mask_types(self) -> tuple[int, ...]:
        """Per FAP group, the mask type the stream goes out with: none, all, interpolate or hold."""
        return tuple(int(t) for t in self.stream.group_mask_types()[0]) if len(self.stream) else ()

    @property
    def speech(self):
        return self.utterance.speech


def _moving(values: np.ndarray) -> np.ndarray:
    """Columns of the low-level FAPs (3-68) that move anywhere in ``values``."""
    used = np.abs(values).max(axis=0) > 0
    used[:2] = False
    return np.flatnonzero(used)


ENGINES = ("espeak", "pyttsx3", "estimate")


def make_engine(name: str) -> Engine:
    """An engine by name: espeak (phoneme times), pyttsx3 (word boundaries), estimate (silent)."""
    if name == "espeak":
        from mpeg4fa.speech.tts.espeak import EspeakEngine
        return EspeakEngine()
    if name == "pyttsx3":
        from mpeg4fa.speech.tts.pyttsx3_engine import Pyttsx3Engine
        return Pyttsx3Engine()
    if name == "estimate":
        from mpeg4fa.speech.tts.estimate import EstimateEngine
        return EstimateEngine()
    from mpeg4fa.speech.errors import TTSError
    raise TTSError(f"unknown engine {name!r}", hint=f"one of {', '.join(ENGINES)}")


def encode_text(text: str, *, engine: Engine | str = "espeak", lang: str = "auto", voice: str | None = None,
                rate: int | None = None, fps: float = 25.0, level: str = "high", idle: bool = False,
                seed: int = 0, name: str = "<text>", fold: bool = True, compact: bool = True) -> Encoded:
    """Speak tagged text and turn it into a FapStream at ``fps`` (see the module docstring for levels).

    ``fold`` leaves out the FAPs the decoder copies from their counterparts (:func:`fold_symmetric`);
    the stream's :attr:`~mpeg4fa.fba.stream.FapStream.mask_types` say so to any encoding of it.
    ``compact`` writes FAP 1 and FAP 2 in the fields cheapest to code and sends FAP 2 only where
    that makes the stream smaller (:mod:`.compact`); the decoded face is the same either way.
    """
    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    markup = parse_markup(text, name=name)
    utterance = speak(markup, make_engine(engine) if isinstance(engine, str) else engine, lang=lang, voice=voice,
                      rate=rate)
    return encode_utterance(utterance, fps=fps, level=level, idle=idle, seed=seed, fold=fold, compact=compact)


def encode_recording(recording, transcript: str, *, lang: str = "auto", voice: str | None = None,
                     rate: int | None = None, method: str = "auto", fps: float = 25.0, level: str = "high",
                     idle: bool = False, seed: int = 0, name: str = "<transcript>", fold: bool = True,
                     compact: bool = True, fit_check: bool = True) -> Encoded:
    """A recording (WAV path or :class:`~mpeg4fa.speech.align.Recording`) and its tagged transcript -> the
    FapStream of the face saying it in time with the recording (:func:`mpeg4fa.speech.align.align_recording`:
    ``method`` auto, pocketsphinx or dtw; ``voice``/``rate`` espeak-ng's reference; ``fit_check`` False aligns
    a transcript whose words do not fit the recording anyway). The Encoded's speech is
    the recording's own audio (mono, at its rate); the rest is :func:`encode_text`'s path.
    """
    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    from mpeg4fa.speech.align import align_recording

    aligned = align_recording(recording, transcript, lang=lang, voice=voice, rate=rate, method=method, name=name,
                              fit_check=fit_check)
    return encode_utterance(aligned.utterance, fps=fps, level=level, idle=idle, seed=seed, fold=fold,
                            compact=compact)


def encode_utterance(utterance: Utterance, *, fps: float = 25.0, level: str = "high", idle: bool = False,
                     seed: int = 0, fold: bool = True, compact: bool = True) -> Encoded:
    """The timeline and stream of a timed :class:`Utterance` (spoken by an engine or aligned to a recording):
    stops start at their closure's silence, then viseme, expression (and idle) tracks at ``fps``, coded
    at ``level`` (see :func:`encode_text` for ``fold`` and ``compact``)."""
    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    utterance = replace(utterance, timings=stop_closures(utterance.timings, utterance.speech))
    times = frame_times(utterance.speech.duration, fps)
    spans, cues = utterance.spans(), list(utterance.cues)
    hold = closure_hold(fps)
    visemes, expressions = viseme_track(spans, times, closure_hold=hold), expression_track(cues, times)
    tracks = [visemes, expressions] + ([idle_track(times, seed)] if idle else [])
    values = np.rint(merge_tracks(*tracks))

    n = len(times)
    stream = FapStream.empty(n)
    stream.source_fps = fps
    stream.timestamps[:] = times
    if level in ("low", "both"):
        used = _moving(values)
        stream.fap_mask[:, used] = True
        stream.fap_values[:, used] = values[:, used]
    if level in ("high", "both"):
        _high_level(stream, utterance, times, values, level, hold, compact)
    if fold:
        fold_symmetric(stream)
    if compact and level in ("high", "both"):  # last: the choice is made on the stream as it will be coded
        stream = plan_expression_mask(stream, stream.expression.copy(), EncodeOptions(**TEXT_CODING))
    return Encoded(stream, utterance, values, level)


def closure_hold(fps: float) -> float:
    """How long a closure (p, b, m) stays shut: :data:`CLOSURE_HOLD`, or one frame if frames are longer,
    so that a frame always shows it."""
    return max(CLOSURE_HOLD, 1.0 / fps)


def _high_level(stream: FapStream, utterance: Utterance, times: np.ndarray, values: np.ndarray, level: str,
                hold: float, compact: bool = True) -> None:
    """FAP 1 and 2 fields; frames whose visemes or expressions they cannot name get low-level FAPs.

    FAP 1 comes from the same moves as the low-level track (same spans, same closure hold).
    With ``compact`` the fields are rewritten to the cheapest equivalent ones (:mod:`.compact`)."""
    same = lambda rows: rows  # noqa: E731
    quant = TEXT_CODING["fap_quant"]
    visemes, expressions = ((partial(compact_visemes, fap_quant=quant), partial(compact_expressions, fap_quant=quant))
                            if compact else (same, same))
    vis = viseme_fields(utterance.spans(), times, closure_hold=hold)
    exp = expression_fields(list(utterance.cues), times)
    n = len(times)
    standard_vis = np.array([a[0] == "mpeg4" and b[0] == "mpeg4" for a, b in zip(vis.select1, vis.select2)])
    select1 = np.array([_VISEME_CODE[s[1]] if ok else 0 for s, ok in zip(vis.select1, standard_vis)])
    select2 = np.array([_VISEME_CODE[s[1]] if ok else 0 for s, ok in zip(vis.select2, standard_vis)])
    names = {s[1] for s, ok in zip(vis.select1 + vis.select2, np.r_[standard_vis, standard_vis]) if ok}
    if names - {"none"}:  # all-Chinese speech leaves FAP 1 nothing to name
        stream.fap_mask[:, 0] = True
        stream.viseme[:] = visemes(
            np.c_[select1, select2, np.where(standard_vis, vis.blend, FULL_INTENSITY), np.zeros(n)])
    known = np.array([[s in _EXPRESSION_CODE for s in col] for col in (exp.select1, exp.select2)]).all(axis=0)
    stream.fap_mask[:, 1] = True  # in every frame until encode_text plans where FAP 2 must go
    stream.expression[:] = expressions(np.c_[
        [_EXPRESSION_CODE.get(s, 0) for s in exp.select1], np.where(known, exp.intensity1, 0),
        [_EXPRESSION_CODE.get(s, 0) for s in exp.select2], np.where(known, exp.intensity2, 0), np.zeros((n, 2))])
    if level == "high":
        low = ~standard_vis | ~known
        if low.any():  # what those frames need, sent in every frame: a change of FAP mask costs an intra frame
            used = _moving(values[low])
            stream.fap_mask[:, used] = True
            stream.fap_values[:, used] = values[:, used]


def fold_symmetric(stream: FapStream) -> set[int]:
    """Stop sending low-level FAPs a decoder copies from a counterpart; return their FAP groups.

    With mask type 2 (interpolate) an unsent FAP copies its left/right counterpart, else its
    inner/outer lip counterpart (:data:`mpeg4fa.spec.FAP_PARTNERS`). Visemes and expressions are
    symmetric, so about a third of the lip, jaw and brow FAPs can go. Each candidate is left out
    only if the stream then *decodes* to the same values (:func:`mpeg4fa.decoded.resolve`, the
    decoder's own rules, not re-derived here): interpolation also changes the FAPs of the group
    that were never sent, so a group whose unsent FAPs would copy a moving counterpart keeps its
    FAPs (e.g. Mandarin's rounded u-umlaut). Right-side and outer FAPs are tried first (highest
    numbers), so the left and inner ones stay. Sets ``stream.mask_types`` to match.
    """
    sent = stream.fap_mask.any(axis=0)
    types = np.asarray(stream.mask_types if stream.mask_types is not None else (MASK_HOLD,) * len(FAP_GROUP_SLICES))
    with warnings.catch_warnings():  # clamps are said when the stream is played, not while planning
        warnings.simplefilter("ignore", ClampWarning)
        reference = resolve(stream)
        folded_groups: set[int] = set()
        for c in sorted(np.flatnonzero(sent), reverse=True):
            if c < 2 or not any(p >= 0 and sent[p] for p in FAP_PARTNERS[c]):
                continue
            group = int(FAP_GROUP[c])
            trial_types = types.copy()
            trial_types[group - 1] = MASK_INTERPOLATE
            trial = replace(stream, fap_mask=stream.fap_mask.copy(), fap_values=stream.fap_values.copy(),
                            mask_types=tuple(int(t) for t in trial_types))
            trial.fap_mask[:, c] = False
            trial.fap_values[:, c] = 0
            if np.array_equal(resolve(trial), reference):
                stream.fap_mask, stream.fap_values, stream.mask_types = trial.fap_mask, trial.fap_values, trial.mask_types
                types = trial_types
                sent[c] = False
                folded_groups.add(group)
    return folded_groups
