"""Layer 1 over whole streams: the FAP values a face shows at every frame.

A decoded :class:`~mpeg4fa.fba.stream.FapStream` says which FAPs each frame
*sent*. A face needs all 68 at every frame, so:

* **hold** (mask type 1, and groups not sent at all): an unsent FAP keeps the
  last value sent (0 before the first);
* **interpolate** (mask type 2): an unsent FAP copies its counterpart sent in the
  same frame: left <-> right (``_l_`` <-> ``_r_``), inner <-> outer lip (FAPs
  4-13 <-> 51-60); with no counterpart sent it holds;
* **high level**: FAP 1 (viseme blend) and FAP 2 (expression blend) hold like
  the others and expand through the shared profiles in ``spec/``
  (:func:`mpeg4fa.spec.expand_high_level`); a low-level FAP that the stream has
  sent overrides the high-level value of that FAP;
* **clamp**: a value no face can show (negative on a unidirectional FAP, or
  beyond :mod:`.limits`' bounds) is clamped, and a :class:`.FaceWarning` says so
  once per FAP per stream, with the number of frames and the worst value.

Every rule looks only at the current and earlier frames, so a stream can be
resolved in pieces: :func:`resolve` takes and returns a :class:`ResolveState`,
and :class:`FrameResolver` uses that for live sources, one frame at a time.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Iterator

import warnings

import numpy as np

from mpeg4fa.face.errors import FaceWarning
from mpeg4fa.face.limits import clamp
from mpeg4fa.fba.stream import FapStream, Frame
from mpeg4fa.spec import FAP_GROUP, FAP_PARTNERS, N_FAPS, expand_high_level


PARTNERS = FAP_PARTNERS
"""Interpolation counterparts of each FAP (see :data:`mpeg4fa.spec.FAP_PARTNERS`)."""


def _last_sent(mask: np.ndarray) -> np.ndarray:
    """Index of the last frame at or before each frame where the column was sent (-1: never)."""
    n = len(mask)
    idx = np.where(mask, np.arange(n)[:, None], -1)
    return np.maximum.accumulate(idx, axis=0)


@dataclass
class ResolveState:
    """What the frames so far leave behind for the next ones: mask types and held values."""

    mask_types: np.ndarray = field(default_factory=lambda: np.ones(N_FAPS, dtype=np.int8))
    held: np.ndarray = field(default_factory=lambda: np.zeros(N_FAPS))
    known: np.ndarray = field(default_factory=lambda: np.zeros(N_FAPS, dtype=bool))
    viseme: np.ndarray = field(default_factory=lambda: np.zeros(4, dtype=np.int32))
    expression: np.ndarray = field(default_factory=lambda: np.zeros(6, dtype=np.int32))
    frames: int = 0  # frames resolved so far
    warned: set[int] = field(default_factory=set)  # FAPs already said to be clamped in this stream
    live: bool = False  # frames come one piece at a time: a clamp is said when first seen


def _mask_types(stream: FapStream, initial: np.ndarray) -> np.ndarray:
    """``(n, 68)`` mask type governing each FAP at each frame (from the latest intra header)."""
    n = stream.n_frames
    per_frame = np.repeat(initial[None, :], n, axis=0)
    group_of = np.asarray(FAP_GROUP) - 1
    for start in sorted(stream.intra):
        face = stream.intra[start].face
        if face is not None:
            per_frame[start:] = np.asarray(face.mask_types, dtype=np.int8)[group_of]
    return per_frame


def _held(last: np.ndarray, table: np.ndarray, before: np.ndarray, known_before: np.ndarray) -> np.ndarray:
    """Rows of ``table`` at ``last``; where nothing was sent in this piece, the value carried in."""
    carried = np.where(known_before, before, 0)
    return np.where(last >= 0, table[np.maximum(last, 0), np.arange(table.shape[1])[None, :]], carried)


def resolve(stream: FapStream, state: ResolveState | None = None) -> np.ndarray:
    """``(n, 68)`` float FAP values to show at each frame (columns 0/1 stay 0).

    ``state`` carries the earlier frames' effect into this piece of a stream and is
    updated in place to this piece's end (pass a fresh one, or none, for a whole stream).
    """
    state = ResolveState() if state is None else state
    n = stream.n_frames
    mask = stream.fap_mask.astype(bool)
    values = stream.fap_values.astype(np.float64)
    if n == 0:
        return np.zeros((0, N_FAPS))
    types = _mask_types(stream, state.mask_types)
    copied = values.copy()
    copy = np.zeros_like(mask)
    for k in (1, 0):  # the left/right partner wins over the inner/outer one
        has = PARTNERS[:, k] >= 0
        cols_k = np.where(has, PARTNERS[:, k], 0)
        take = (types == 2) & ~mask & mask[:, cols_k] & has[None, :]
        copied = np.where(take, values[:, cols_k], copied)
        copy |= take
    # an interpolated value counts as sent: it holds like one
    last = _last_sent(mask | copy)
    out = _held(last, copied, state.held, state.known)
    low_level_known = (last >= 0) | state.known
    low_level_known[:, :2] = False

    vis_last = np.repeat(_last_sent(mask[:, :1]), 4, axis=1)
    exp_last = np.repeat(_last_sent(mask[:, 1:2]), 6, axis=1)
    viseme = _held(vis_last, stream.viseme, state.viseme, np.ones(4, bool)).astype(np.int64)
    expression = _held(exp_last, stream.expression, state.expression, np.ones(6, bool)).astype(np.int64)
    if viseme.any() or expression.any():
        high = expand_high_level(viseme, expression)
        out = np.where(low_level_known, out, high)
    out[:, :2] = 0.0
    out = _clamp_and_say(out, state)

    state.mask_types = types[-1].copy()
    state.held = out[-1].copy()
    state.known = low_level_known[-1].copy()
    state.held[:2], state.known[:2] = 0.0, False
    state.viseme, state.expression = viseme[-1].copy(), expression[-1].copy()
    state.frames += n
    return out


def _clamp_and_say(values: np.ndarray, state: ResolveState) -> np.ndarray:
    """Values held inside what a face shows; one warning per FAP per stream (the first piece that needs it)."""
    clamped, report = clamp(values)
    for item in report:
        if item.fap in state.warned:
            continue
        state.warned.add(item.fap)
        where = f"the stream from frame {state.frames} on (later frames not counted)" if state.live else "the stream"
        warnings.warn(item.message(where), FaceWarning, stacklevel=3)
    return clamped


class FrameResolver:
    """:func:`resolve` for a live source: one decoded :class:`Frame` in, its 68 values out."""

    def __init__(self) -> None:
        self.state = ResolveState(live=True)

    def push(self, frame: Frame) -> np.ndarray:
        return resolve(FapStream.from_frames([frame]), self.state)[0]

    def resolve_all(self, frames: Iterable[Frame]) -> Iterator[np.ndarray]:
        for frame in frames:
            yield self.push(frame)
