"""The FAP values a decoder shows at every frame of a stream (layer 1 of the face).

A decoded :class:`~mpeg4fa.fba.stream.FapStream` says which FAPs each frame
*sent*. A face needs all 68 at every frame, so:

* **hold** (mask type 1, and groups not sent at all): an unsent FAP keeps the
  last value sent (0 before the first);
* **interpolate** (mask type 2): an unsent FAP copies its counterpart sent in the
  same frame: left <-> right, then inner <-> outer lip
  (:data:`mpeg4fa.spec.FAP_PARTNERS`); with no counterpart sent it holds. The
  mask type governing a frame is the latest intra header's, or the stream's
  intended :attr:`~mpeg4fa.fba.stream.FapStream.mask_types` before any
  (:meth:`~mpeg4fa.fba.stream.FapStream.group_mask_types`);
* **high level**: FAP 1 (viseme blend) and FAP 2 (expression blend) hold like
  the others and expand through the shared profiles in ``spec/``
  (:func:`mpeg4fa.spec.expand_high_level`); a low-level FAP that the stream has
  sent overrides the high-level value of that FAP;
* **clamp**: a value no face can show (negative on a unidirectional FAP, or
  beyond :mod:`.limits`' bounds) is clamped, and a :class:`.ClampWarning` says so
  once per FAP per stream, with the number of frames and the worst value.

Every rule looks only at the current and earlier frames, so a stream can be
resolved in pieces: :func:`resolve` takes and returns a :class:`ResolveState`,
:class:`FrameResolver` uses that for live sources, one frame at a time, and
:func:`shown_frame` gives one frame of a stream with the frames before it.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from typing import Iterable, Iterator, Mapping

import numpy as np

from mpeg4fa.decoded.errors import ClampWarning, FapValueError
from mpeg4fa.decoded.limits import check_finite, clamp, clamp_and_warn
from mpeg4fa.fba.stream import ARRAY_FIELDS, FapStream, Frame
from mpeg4fa.spec import FAP_GROUP, FAP_PARTNERS, N_FAPS, expand_high_level, expression_blend, viseme_blend

MASK_INTERPOLATE = 2
_GROUP_OF = np.asarray(FAP_GROUP) - 1  # column -> FAP group index


def _last_sent(mask: np.ndarray) -> np.ndarray:
    """Index of the last frame at or before each frame where the column was sent (-1: never)."""
    n = len(mask)
    idx = np.where(mask, np.arange(n)[:, None], -1)
    return np.maximum.accumulate(idx, axis=0)


@dataclass
class ResolveState:
    """What the frames so far leave behind for the next ones: held values and high-level fields."""

    held: np.ndarray = field(default_factory=lambda: np.zeros(N_FAPS))
    known: np.ndarray = field(default_factory=lambda: np.zeros(N_FAPS, dtype=bool))
    viseme: np.ndarray = field(default_factory=lambda: np.zeros(4, dtype=np.int32))
    expression: np.ndarray = field(default_factory=lambda: np.zeros(6, dtype=np.int32))
    group_types: np.ndarray | None = None  # mask types (10) governing the next frame; None: the stream's own
    frames: int = 0  # frames resolved so far
    warned: set[int] = field(default_factory=set)  # FAPs already said to be clamped in this stream
    live: bool = False  # frames come one piece at a time: a clamp is said when first seen


def _held(last: np.ndarray, table: np.ndarray, before: np.ndarray, known_before: np.ndarray) -> np.ndarray:
    """Rows of ``table`` at ``last``; where nothing was sent in this piece, the value carried in."""
    carried = np.where(known_before, before, 0)
    return np.where(last >= 0, table[np.maximum(last, 0), np.arange(table.shape[1])[None, :]], carried)


def _group_types(stream: FapStream, state: ResolveState) -> np.ndarray:
    """``(n, 10)`` mask types; frames before this piece's first intra header keep the state's."""
    types = stream.group_mask_types()
    if state.group_types is not None and len(types):
        first_intra = min((k for k in stream.intra if stream.intra[k].face is not None), default=len(types))
        types[:first_intra] = state.group_types
    return types


def resolve(stream: FapStream, state: ResolveState | None = None) -> np.ndarray:
    """``(n, 68)`` float FAP values to show at each frame (columns 0/1 stay 0).

    ``state`` carries the earlier frames' effect into this piece of a stream and is
    updated in place to this piece's end (pass a fresh one, or none, for a whole stream).
    """
    state = ResolveState() if state is None else state
    n = stream.n_frames
    if n == 0:
        return np.zeros((0, N_FAPS))
    mask = stream.fap_mask.astype(bool)
    values = stream.fap_values.astype(np.float64)
    group_types = _group_types(stream, state)
    copied, copy = _interpolate(mask, values, group_types)
    # an interpolated value counts as sent: it holds like one
    last = _last_sent(mask | copy)
    out = _held(last, copied, state.held, state.known)
    low_level_known = (last >= 0) | state.known
    low_level_known[:, :2] = False

    viseme, expression = held_high_level(stream, state)
    if viseme.any() or expression.any():
        out = _over_high_level(out, low_level_known, expand_high_level(viseme, expression))
    out[:, :2] = 0.0
    out = _clamp_and_say(out, state)

    state.group_types = group_types[-1].copy()
    state.held = out[-1].copy()
    state.known = low_level_known[-1].copy()
    state.held[:2], state.known[:2] = 0.0, False
    state.viseme, state.expression = viseme[-1].copy(), expression[-1].copy()
    state.frames += n
    return out


def held_high_level(stream: FapStream, state: ResolveState | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(n, 4)`` FAP 1 and ``(n, 6)`` FAP 2 fields each frame shows: the last sent, held across frames that
    do not send them (from ``state``'s, else zeros, before the first); ``state`` is not changed."""
    state = ResolveState() if state is None else state
    mask = stream.fap_mask.astype(bool)
    vis_last = np.repeat(_last_sent(mask[:, :1]), 4, axis=1)
    exp_last = np.repeat(_last_sent(mask[:, 1:2]), 6, axis=1)
    viseme = _held(vis_last, stream.viseme, state.viseme, np.ones(4, bool)).astype(np.int64)
    expression = _held(exp_last, stream.expression, state.expression, np.ones(6, bool)).astype(np.int64)
    return viseme, expression


def _interpolate(mask: np.ndarray, values: np.ndarray, group_types: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values with interpolated FAPs filled in from their counterparts, and where that happened."""
    types = group_types[:, _GROUP_OF]
    copied = values.copy()
    copy = np.zeros_like(mask)
    for k in (1, 0):  # the left/right partner wins over the inner/outer one
        has = FAP_PARTNERS[:, k] >= 0
        cols_k = np.where(has, FAP_PARTNERS[:, k], 0)
        take = (types == MASK_INTERPOLATE) & ~mask & mask[:, cols_k] & has[None, :]
        copied = np.where(take, values[:, cols_k], copied)
        copy |= take
    return copied, copy


def explicit(stream: FapStream) -> FapStream:
    """The stream with every FAP a decoder copies from its counterpart (mask type 2) sent outright,
    and no intra headers: for formats that cannot say "interpolate" (``.fap`` text), so that nothing
    the stream shows is lost. Resolves to the same values as ``stream``."""
    out = stream.copy()
    copied, copy = _interpolate(stream.fap_mask.astype(bool), stream.fap_values, stream.group_mask_types())
    out.fap_mask = stream.fap_mask | copy
    out.fap_values = copied.astype(stream.fap_values.dtype)
    out.source_fps, out.intra, out.mask_types = stream.fps, {}, None
    return out


def _over_high_level(low: np.ndarray, sent: np.ndarray, high: np.ndarray) -> np.ndarray:
    """The high-level values, overridden wherever the low-level FAP has been sent."""
    return np.where(sent, low, high)


def _clamp_and_say(values: np.ndarray, state: ResolveState) -> np.ndarray:
    """Values held inside what a face shows; one warning per FAP per stream (the first piece that needs it)."""
    clamped, report = clamp(values)
    for item in report:
        if item.fap in state.warned:
            continue
        state.warned.add(item.fap)
        where = f"the stream from frame {state.frames} on (later frames not counted)" if state.live else "the stream"
        warnings.warn(item.message(where), ClampWarning, stacklevel=3)
    return clamped


def _prefix(stream: FapStream, stop: int) -> FapStream:
    """Frames ``0 .. stop-1`` of ``stream`` with their intra headers."""
    arrays = {name: getattr(stream, name)[:stop] for name in ARRAY_FIELDS}
    return replace(stream, intra={k: p for k, p in stream.intra.items() if k < stop}, **arrays)


def shown_frame(frame: Frame) -> np.ndarray:
    """The 68 values one frame shows. A frame of a stream (:meth:`FapStream.frame`) is resolved with the
    frames before it, so it shows what :func:`resolve` gives for its row; a frame read on its own starts
    from neutral. Clamps are said about this frame only."""
    state = ResolveState()
    stream, k = frame.stream, frame.index
    if stream is None or not 0 <= k < len(stream):
        return resolve(FapStream.from_frames([frame]), state)[0]
    with warnings.catch_warnings():  # the earlier frames' clamps are not this frame's news
        warnings.simplefilter("ignore", ClampWarning)
        resolve(_prefix(stream, k), state)
    state.warned = set()
    piece = stream.take([k])
    piece.intra = {0: stream.intra[k]} if k in stream.intra else {}
    return resolve(piece, state)[0]


def shown_values(faps: "Mapping[int, float] | np.ndarray | None" = None, *, viseme: tuple[str, str] | None = None,
                 expression: tuple[str, int] | None = None) -> np.ndarray:
    """The 68 values a face shows for low-level FAPs plus an optional viseme ``(set, name)`` at full blend
    and expression ``(name, intensity 0..63)``, by the same rules as a stream: the profiles in ``spec/``
    and the low-level FAPs given override the high-level ones. Values no face can show are clamped, said."""
    if faps is None:
        low, sent = np.zeros(N_FAPS), np.zeros(N_FAPS, dtype=bool)
    elif isinstance(faps, Mapping):
        low, sent = np.zeros(N_FAPS), np.zeros(N_FAPS, dtype=bool)
        for fap, value in faps.items():
            if not 3 <= int(fap) <= N_FAPS:
                raise FapValueError(f"FAP {fap} is not a low-level FAP", where=f"FAP {fap}",
                                    hint="low-level FAPs are 3..68; use a viseme or expression for 1 and 2")
            low[int(fap) - 1], sent[int(fap) - 1] = value, True
    else:
        low = np.array(faps, dtype=np.float64)
        if low.shape != (N_FAPS,):
            raise FapValueError(f"a frame has {N_FAPS} FAP values, got shape {low.shape}",
                                hint="pass an array of 68 values or a {fap: value} mapping")
        sent = low != 0
    check_finite(low)
    high = np.zeros(N_FAPS)
    if viseme is not None:
        set_name, name = viseme
        high += _profile("viseme", viseme_blend, name, name, 0, set=set_name)  # one viseme: any blend
    if expression is not None:
        name, intensity = expression
        high += _profile("expression", expression_blend, name, intensity, "neutral", 0)
    values = _over_high_level(low, sent, high)
    values[:2] = 0.0
    return clamp_and_warn(values, None, stacklevel=3)


def _profile(what: str, blend, *args, **kwargs) -> np.ndarray:
    """A spec profile blend; the spec's complaint about a name or level said as this layer's error."""
    try:
        return blend(*args, **kwargs)
    except ValueError as exc:
        raise FapValueError(str(exc), where=what) from None


class FrameResolver:
    """:func:`resolve` for a live source: one decoded :class:`Frame` in, its 68 values out."""

    def __init__(self) -> None:
        self.state = ResolveState(live=True)

    def push(self, frame: Frame) -> np.ndarray:
        return resolve(FapStream.from_frames([frame]), self.state)[0]

    def resolve_all(self, frames: Iterable[Frame]) -> Iterator[np.ndarray]:
        for frame in frames:
            yield self.push(frame)
