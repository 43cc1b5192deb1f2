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
from mpeg4fa.spec import EXPRESSIONS, FAP_GROUP, FAP_GROUP_SLICES, FAP_PARTNERS, FULL_INTENSITY, N_FAPS, VISEMES
from mpeg4fa.speech.closures import stop_closures
from mpeg4fa.speech.compact import compact_expressions, compact_visemes, plan_expression_mask
from mpeg4fa.speech.frames import FrameBlock, FrameMaker, join_blocks
from mpeg4fa.speech.timeline import CLOSURE_HOLD
from mpeg4fa.speech.tts.base import Engine
from mpeg4fa.speech.utterance import Utterance

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
                seed: int = 0, name: str = "<text>", fold: bool = True, compact: bool = True,
                max_seconds: float | None = None, progress=None, **markup_options) -> Encoded:
    """Speak tagged text and turn it into a FapStream at ``fps`` (see the module docstring for levels).

    ``fold`` leaves out the FAPs the decoder copies from their counterparts (:func:`fold_symmetric`);
    the stream's :attr:`~mpeg4fa.fba.stream.FapStream.mask_types` say so to any encoding of it.
    ``compact`` writes FAP 1 and FAP 2 in the fields cheapest to code and sends FAP 2 only where
    that makes the stream smaller (:mod:`.compact`); the decoded face is the same either way.

    The text goes through the passes of :mod:`.pipeline` in chunks of sentences and is kept in
    memory (use :func:`~.pipeline.encode_text_to` for long text): ``max_seconds`` refuses speech
    longer than that where it runs over; ``progress(done, total)`` counts characters;
    ``markup_options`` go to :func:`~.markup.parse_markup`.
    """
    from mpeg4fa.speech.pipeline import encoded_text

    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    return encoded_text(text, make_engine(engine) if isinstance(engine, str) else engine, fps=fps, level=level,
                        idle=idle, seed=seed, name=name, fold=fold, compact=compact, lang=lang, voice=voice,
                        rate=rate, max_seconds=max_seconds, progress=progress, **markup_options)


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
    at ``level`` (see :func:`encode_text` for ``fold`` and ``compact``).

    The same passes as long text (:mod:`.pipeline`): phones (:func:`phones`) -> frames
    (:class:`~.frames.FrameMaker`) -> stream (:class:`StreamBuilder`), here on one utterance, in memory."""
    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    utterance = phones(utterance)
    maker = FrameMaker(fps, idle=idle, seed=seed, closure_hold=closure_hold(fps), fields=level != "low")
    duration = utterance.speech.duration
    blocks = [maker.add(utterance.spans(), utterance.cues, duration), maker.finish(duration)]
    block = join_blocks([b for b in blocks if b is not None])
    stream = StreamBuilder(level, fps, fold=fold, compact=compact).build(block)
    return Encoded(stream, utterance, block.values, level)


def phones(utterance: Utterance) -> Utterance:
    """The phones pass: stops start at their closure's silence (:func:`~.closures.stop_closures`)."""
    return replace(utterance, timings=stop_closures(utterance.timings, utterance.speech))


def closure_hold(fps: float) -> float:
    """How long a closure (p, b, m) stays shut: :data:`CLOSURE_HOLD`, or one frame if frames are longer,
    so that a frame always shows it."""
    return max(CLOSURE_HOLD, 1.0 / fps)


class StreamBuilder:
    """The stream pass: frames -> the FapStream that carries them at ``level`` (see the module docstring).

    A long text's frames come in blocks, each coded as a stream of its own that starts with an intra
    frame (:mod:`.bits` joins their bits). What a decoder holds across a block boundary is kept
    here, so the blocks decode as one stream would: a low-level FAP sent once is sent in every later
    block (a FAP left out holds its last value), FAP 1 likewise, and FAP 2 goes out in a block's
    first frame whenever the decoder holds other fields than the neutral zeros the planner assumes.
    One block (a short text) is coded exactly as before the streaming.
    """

    def __init__(self, level: str, fps: float, *, fold: bool = True, compact: bool = True) -> None:
        if level not in LEVELS:
            raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
        self.level, self.fps, self.fold, self.compact = level, fps, fold, compact
        self.low = np.zeros(N_FAPS, dtype=bool)        # low-level FAPs sent so far (level low, both)
        self.low_for_high = np.zeros(N_FAPS, dtype=bool)  # low-level FAPs a high-level stream had to send
        self.fap1 = False
        self.held_expression = np.zeros(6, dtype=np.int64)  # FAP 2 fields the decoder holds

    def build(self, block: FrameBlock) -> FapStream:
        times, values, level = block.times, block.values, self.level
        n = len(times)
        stream = FapStream.empty(n)
        stream.source_fps = self.fps
        stream.timestamps[:] = times
        if level in ("low", "both"):
            self.low |= _moving_mask(values)
            used = np.flatnonzero(self.low)
            stream.fap_mask[:, used] = True
            stream.fap_values[:, used] = values[:, used]
        if level in ("high", "both"):
            self._high_level(stream, block, values)
        if self.fold:
            fold_symmetric(stream)
        if self.compact and level in ("high", "both"):  # last: the choice is made on the stream as it will be coded
            expression = stream.expression.copy()
            stream = plan_expression_mask(stream, expression, EncodeOptions(**TEXT_CODING))
            if self.held_expression.any() and not stream.fap_mask[0, 1]:  # the planner assumed zeros held
                stream.fap_mask[0, 1] = True
                stream.expression[0] = expression[0]
        if level in ("high", "both"):
            sent = np.flatnonzero(stream.fap_mask[:, 1])
            if len(sent):
                self.held_expression = stream.expression[sent[-1]].astype(np.int64)
        return stream

    def _high_level(self, stream: FapStream, block: FrameBlock, values: np.ndarray) -> None:
        """FAP 1 and 2 fields; frames whose visemes or expressions they cannot name get low-level FAPs.

        FAP 1 comes from the same moves as the low-level track (same spans, same closure hold).
        With ``compact`` the fields are rewritten to the cheapest equivalent ones (:mod:`.compact`)."""
        same = lambda rows: rows  # noqa: E731
        quant = TEXT_CODING["fap_quant"]
        visemes, expressions = ((partial(compact_visemes, fap_quant=quant),
                                 partial(compact_expressions, fap_quant=quant)) if self.compact else (same, same))
        vis, exp = block.visemes, block.expressions
        n = len(block)
        standard_vis = np.array([a[0] == "mpeg4" and b[0] == "mpeg4" for a, b in zip(vis.select1, vis.select2)],
                                dtype=bool)
        select1 = np.array([_VISEME_CODE[s[1]] if ok else 0 for s, ok in zip(vis.select1, standard_vis)])
        select2 = np.array([_VISEME_CODE[s[1]] if ok else 0 for s, ok in zip(vis.select2, standard_vis)])
        names = {s[1] for s, ok in zip(vis.select1 + vis.select2, np.r_[standard_vis, standard_vis]) if ok}
        if names - {"none"} or self.fap1:  # all-Chinese speech leaves FAP 1 nothing to name
            self.fap1 = True
            stream.fap_mask[:, 0] = True
            stream.viseme[:] = visemes(
                np.c_[select1, select2, np.where(standard_vis, vis.blend, FULL_INTENSITY), np.zeros(n)])
        known = np.array([[s in _EXPRESSION_CODE for s in col] for col in (exp.select1, exp.select2)]).all(axis=0)
        stream.fap_mask[:, 1] = True  # in every frame until the plan says where FAP 2 must go
        stream.expression[:] = expressions(np.c_[
            [_EXPRESSION_CODE.get(s, 0) for s in exp.select1], np.where(known, exp.intensity1, 0),
            [_EXPRESSION_CODE.get(s, 0) for s in exp.select2], np.where(known, exp.intensity2, 0), np.zeros((n, 2))])
        if self.level == "high":
            low = ~standard_vis | ~known
            if low.any():  # what those frames need, sent in every frame: a change of FAP mask costs an intra frame
                self.low_for_high |= _moving_mask(values[low])
            used = np.flatnonzero(self.low_for_high)
            if len(used):
                stream.fap_mask[:, used] = True
                stream.fap_values[:, used] = values[:, used]


def _moving_mask(values: np.ndarray) -> np.ndarray:
    """Which low-level FAPs (3-68) move anywhere in ``values`` (68 booleans)."""
    used = np.abs(values).max(axis=0) > 0 if len(values) else np.zeros(N_FAPS, dtype=bool)
    used[:2] = False
    return used


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
