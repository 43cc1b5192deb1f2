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

from dataclasses import dataclass, replace

import numpy as np

from mpeg4fa.fba import EncodeOptions
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.fba.syntax import MASK_ALL, MASK_HOLD, MASK_INTERPOLATE, MASK_NONE
from mpeg4fa.spec import EXPRESSIONS, FAP_GROUP, FAP_GROUP_SLICES, FAP_PARTNERS, VISEMES
from mpeg4fa.speech.closures import stop_closures
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
    """What the encoder made: the FAP stream, the speech it goes with, and the timeline behind it."""

    stream: FapStream
    utterance: Utterance
    values: np.ndarray  # (n, 68) merged low-level FAP values the stream stands for
    level: str
    mask_types: tuple[int, ...]  # per FAP group: how the decoder must read unsent FAPs

    def coding(self, **overrides) -> EncodeOptions:
        """The options to encode :attr:`stream` with: ``TEXT_CODING``, these mask types, then ``overrides``."""
        return EncodeOptions(**{**TEXT_CODING, "mask_types": self.mask_types, **overrides})

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
                seed: int = 0, name: str = "<text>", fold: bool = True) -> Encoded:
    """Speak tagged text and turn it into a FapStream at ``fps`` (see the module docstring for levels).

    ``fold`` leaves out the FAPs the decoder can copy from their counterparts (:func:`fold_symmetric`);
    encode the stream with :meth:`Encoded.coding` so their groups are sent with mask type 2.
    """
    if level not in LEVELS:
        raise ValueError(f"level {level!r}: one of {', '.join(LEVELS)}")
    markup = parse_markup(text, name=name)
    utterance = speak(markup, make_engine(engine) if isinstance(engine, str) else engine, lang=lang, voice=voice,
                      rate=rate)
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
        _high_level(stream, utterance, times, values, level, hold)
    interpolated = fold_symmetric(stream) if fold else set()
    return Encoded(stream, utterance, values, level, _mask_types(stream, interpolated))


def closure_hold(fps: float) -> float:
    """How long a closure (p, b, m) stays shut: :data:`CLOSURE_HOLD`, or one frame if frames are longer,
    so that a frame always shows it."""
    return max(CLOSURE_HOLD, 1.0 / fps)


def _high_level(stream: FapStream, utterance: Utterance, times: np.ndarray, values: np.ndarray, level: str,
                hold: float) -> None:
    """FAP 1 and 2 fields; frames whose visemes or expressions they cannot name get low-level FAPs.

    FAP 1 comes from the same moves as the low-level track (same spans, same closure hold)."""
    vis = viseme_fields(utterance.spans(), times, closure_hold=hold)
    exp = expression_fields(list(utterance.cues), times)
    n = len(times)
    standard_vis = np.array([a[0] == "mpeg4" and b[0] == "mpeg4" for a, b in zip(vis.select1, vis.select2)])
    select1 = np.array([_VISEME_CODE[s[1]] if ok else 0 for s, ok in zip(vis.select1, standard_vis)])
    select2 = np.array([_VISEME_CODE[s[1]] if ok else 0 for s, ok in zip(vis.select2, standard_vis)])
    names = {s[1] for s, ok in zip(vis.select1 + vis.select2, np.r_[standard_vis, standard_vis]) if ok}
    if names - {"none"}:  # all-Chinese speech leaves FAP 1 nothing to name
        stream.fap_mask[:, 0] = True
        stream.viseme[:] = np.c_[select1, select2, np.where(standard_vis, vis.blend, 63), np.zeros(n)]
    known = np.array([[s in _EXPRESSION_CODE for s in col] for col in (exp.select1, exp.select2)]).all(axis=0)
    stream.fap_mask[:, 1] = True
    stream.expression[:] = np.c_[
        [_EXPRESSION_CODE.get(s, 0) for s in exp.select1], np.where(known, exp.intensity1, 0),
        [_EXPRESSION_CODE.get(s, 0) for s in exp.select2], np.where(known, exp.intensity2, 0), np.zeros((n, 2))]
    if level == "high":
        low = ~standard_vis | ~known
        if low.any():  # what those frames need, sent in every frame: a change of FAP mask costs an intra frame
            used = _moving(values[low])
            stream.fap_mask[:, used] = True
            stream.fap_values[:, used] = values[:, used]


def fold_symmetric(stream: FapStream) -> set[int]:
    """Stop sending low-level FAPs the decoder can copy from a counterpart; return their FAP groups.

    With mask type 2 (interpolate) an unsent FAP copies its left/right counterpart if that is
    sent, else its inner/outer lip counterpart (:data:`mpeg4fa.spec.FAP_PARTNERS`, the rule
    the decoder applies). Visemes and expressions are symmetric, so about a third of the
    lip, jaw and brow FAPs go. A FAP is dropped only where the counterpart the decoder will
    choose is sent in the same frames with the same values, and that counterpart then stays.
    Right-side and outer FAPs are tried first (highest numbers), so the left and inner ones stay.
    """
    sent = stream.fap_mask.any(axis=0)
    pinned = np.zeros_like(sent)
    folded_groups: set[int] = set()
    for c in sorted(np.flatnonzero(sent), reverse=True):
        if c < 2 or pinned[c]:
            continue
        choice = next((int(p) for p in FAP_PARTNERS[c] if p >= 0 and sent[p]), None)
        if choice is None:
            continue
        same_mask = np.array_equal(stream.fap_mask[:, c], stream.fap_mask[:, choice])
        if same_mask and np.array_equal(stream.fap_values[:, c], stream.fap_values[:, choice]):
            sent[c] = False
            pinned[choice] = True
            stream.fap_mask[:, c] = False
            stream.fap_values[:, c] = 0
            folded_groups.add(int(FAP_GROUP[c]))
    return folded_groups


def _mask_types(stream: FapStream, interpolated: set[int]) -> tuple[int, ...]:
    """Per FAP group: none, all, or partly sent (interpolate where FAPs were folded, else hold)."""
    types = []
    for g, (a, b) in enumerate(FAP_GROUP_SLICES, start=1):
        cols = stream.fap_mask[:, a:b]
        if not cols.any():
            types.append(MASK_NONE)
        elif cols.all():
            types.append(MASK_ALL)
        else:
            types.append(MASK_INTERPOLATE if g in interpolated else MASK_HOLD)
    return tuple(types)
