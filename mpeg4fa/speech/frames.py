"""The frames pass: timed visemes and expression cues -> FAP frames, one sentence after another.

Why a pass of its own: a long text is spoken in chunks of sentences (:mod:`.chunks`), and the frames
of one chunk must be exactly those the whole text's timeline would give (:mod:`.timeline`), with
expression transitions, the mouth's moves and idle motion running on across chunk boundaries. The
timeline's rules look only a short way ahead (a move starts at most :data:`~.timeline.LEAD` before
its span, a cue acts from its own time on), so after each chunk the frames before a *horizon* are
final: they are handed on and forgotten. Memory stays that of a chunk, whatever the text's length.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mpeg4fa.fba.stream import FrameRate
from mpeg4fa.speech.timeline import (CLOSURE_HOLD, ExpressionCue, ExpressionFields, IdleMotion, VisemeFields,
                                     VisemeSpan, _checked_cues, _checked_spans, _expression_field_rows,
                                     _expression_rows, _ExpressionTracks, _finite, _Moves, _viseme_field_rows,
                                     _viseme_rows, merge_tracks)

WINDOW = 4096
"""Frames computed at once (the tracks take some kB a frame while they are merged)."""
REST_TIME = 0.15
"""The longest move into silence (s), as :func:`~.timeline.viseme_track` defaults it."""


@dataclass(frozen=True)
class FrameBlock:
    """Frames ``first .. first + len(times) - 1`` of the text: times, the merged low-level FAPs (rounded,
    as the stream carries them) and, when asked for, the FAP 1 and FAP 2 fields of the same moves."""

    first: int
    times: np.ndarray
    values: np.ndarray
    visemes: VisemeFields | None
    expressions: ExpressionFields | None

    def __len__(self) -> int:
        return len(self.times)


def frame_count(duration: float, fps: float) -> int:
    """Frames covering ``duration`` (:func:`~.timeline.frame_times`' rule: at least 1)."""
    return max(1, math.ceil(round(duration * fps, 9)))


class FrameMaker:
    """Viseme spans and expression cues in, in time order, chunk by chunk; final frames out.

    ``add`` takes a chunk's spans and cues (seconds from the start of the text) and ``until``, the
    chunk's end: nothing later can come before it. ``finish`` ends the text at ``duration`` seconds.
    Each returns the frames that became final (None when none did).
    """

    def __init__(self, fps: float, *, idle: bool = False, seed: int = 0, closure_hold: float = CLOSURE_HOLD,
                 fields: bool = True) -> None:
        rate = _finite(fps, "fps")
        if rate <= 0:
            raise ValueError(f"need fps > 0, got {fps}")
        FrameRate.from_fps(rate)  # FbaError for a rate no stream carries (1e308 frames would never end)
        self.fps = rate
        self.fields = fields
        self.moves = _Moves(REST_TIME, closure_hold)
        self.segments: list = []
        self.expressions = _ExpressionTracks()
        self.idle = IdleMotion(seed) if idle else None
        self.tail: VisemeSpan | None = None  # the last span, kept back: the next chunk's first may continue it
        self.next = 0  # the first frame not handed on yet
        self.until = 0.0

    def add(self, spans: Sequence[VisemeSpan], cues: Sequence[ExpressionCue], until: float) -> FrameBlock | None:
        spans = list(spans)
        if spans and self.tail is not None:
            first, tail = spans[0], self.tail
            if first.viseme == tail.viseme and first.set == tail.set and abs(tail.end - first.start) < 1e-9:
                spans[0] = VisemeSpan(tail.viseme, tail.start, first.end, tail.set)  # one span, as in one text
            else:
                spans.insert(0, tail)
            self.tail = None
        elif self.tail is not None:
            spans = [self.tail]
            self.tail = None
        if spans:
            *fed, self.tail = spans
            for phase in _checked_spans(fed):
                self.segments += self.moves.add(phase)
        self.expressions.add(_checked_cues(cues))
        self.until = max(self.until, _finite(until, "until"))
        horizon = min(self.moves.horizon, self.until)
        if horizon == -math.inf:
            return None
        stop = min(math.ceil(round(horizon * self.fps, 9)), math.ceil(horizon * self.fps))
        while stop > self.next and (stop - 1) / self.fps >= horizon:
            stop -= 1
        return self._frames(stop) if stop > self.next else None

    def finish(self, duration: float) -> FrameBlock:
        """The frames left, up to the :func:`frame_count` that covers ``duration`` seconds."""
        if self.tail is not None:
            for phase in _checked_spans([self.tail]):
                self.segments += self.moves.add(phase)
            self.tail = None
        self.segments += self.moves.finish()
        stop = frame_count(_finite(duration, "duration"), self.fps)
        return self._frames(max(stop, self.next))

    def _frames(self, stop: int) -> FrameBlock:
        """Frames ``next .. stop - 1``, computed :data:`WINDOW` at a time (the tracks of a long chunk at
        a high frame rate are not all held at once)."""
        parts = []
        while self.next < stop or not parts:
            parts.append(self._window(min(stop, self.next + WINDOW)))
        return join_blocks(parts)

    def _window(self, stop: int) -> FrameBlock:
        first = self.next
        t = np.arange(first, stop, dtype=np.float64) / self.fps
        segments = self.segments
        tracks = [_viseme_rows(segments, t)]
        levels = self.expressions.levels(t)
        tracks.append(_expression_rows(levels))
        if self.idle is not None:
            tracks.append(self.idle(t))
        values = np.rint(merge_tracks(*tracks))
        visemes = _viseme_field_rows(segments, t) if self.fields else None
        expressions = _expression_field_rows(levels) if self.fields else None
        if len(t):  # forget what later frames cannot read
            last = float(t[-1])
            keep = int(np.searchsorted([s.start for s in segments], last, side="right")) - 1
            if keep > 0:
                del segments[:keep]
            self.expressions.forget(last)
            if self.idle is not None:
                self.idle.forget(last)
        self.next = stop
        return FrameBlock(first, t, values, visemes, expressions)


def join_blocks(blocks: Sequence[FrameBlock]) -> FrameBlock:
    """Consecutive frame blocks as one (what a stream of several chunks is built from)."""
    if len(blocks) == 1:
        return blocks[0]
    fields = blocks[0].visemes is not None
    vis = VisemeFields([s for b in blocks for s in b.visemes.select1], [s for b in blocks for s in b.visemes.select2],
                       np.concatenate([b.visemes.blend for b in blocks])) if fields else None
    exp = ExpressionFields(*(np.concatenate([getattr(b.expressions, f) for b in blocks])
                             for f in ("select1", "intensity1", "select2", "intensity2"))) if fields else None
    return FrameBlock(blocks[0].first, np.concatenate([b.times for b in blocks]),
                      np.concatenate([b.values for b in blocks]), vis, exp)
