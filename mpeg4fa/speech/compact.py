"""Fewer bits for the same face: FAP 1 and FAP 2 fields chosen for the codec, FAP 2 sent only when needed.

A high-level stream says *which mixture* of visemes and expressions each frame shows; many field
values say the same mixture, and P frames code each field as a difference from the previous frame
through an adaptive arithmetic model, so a field that keeps its value is nearly free and a frame
that repeats the previous one folds into its skip count. So:

* FAP 1 ``(select1, select2, blend)`` shows ``v1 x blend/63 + v2 x (1 - blend/63)``: with one viseme
  shown (``select1 == select2``, blend 63 or blend 0) the field that does not matter repeats its last
  value, and a two-viseme frame may be written either way round, ``(a, b, x)`` or ``(b, a, 63 - x)``
  (63 is a multiple of the text coding's ``fap_quant`` 3, so both decode alike). Written so, the
  viseme left keeps its slot, one select changes per move, and the blend ramps up and down without
  the jump back to 0 at every move (:func:`compact_visemes`).
* FAP 2 ``(select1, intensity1, select2, intensity2)`` shows ``e1 x i1/63 + e2 x i2/63``: a slot with
  intensity 0 or the neutral expression shows nothing whatever its other field, and the two slots
  may swap (:func:`compact_expressions`).
* FAP 1 and FAP 2 that a frame does not send hold their last values at the decoder
  (:mod:`mpeg4fa.decoded.resolve`), so FAP 2 need only be sent where it changes; but the FAP mask
  travels only in intra headers, and an intra frame (header, ranges, models reset) costs far more
  than a few frames of unchanged FAP 2. :func:`plan_expression_mask` tries a few masks, from "every
  frame" to "only the runs of change", and keeps the one that encodes smallest.

Both field choices are a cheapest path (a beam search over the equivalent ways of writing each
frame) under the codec's own cost: each hypothesis carries the adaptive P models of the fields
(:class:`~mpeg4fa.fba.params.FieldCoder`'s sizes and steps, counts starting uniform as after an
intra frame, one added per coded symbol), a coded symbol costs ``-log2`` of its model probability,
a coded frame :data:`FRAME_BITS` more, a frame equal to the one before :data:`REPEAT_BITS`.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from mpeg4fa.fba import EncodeOptions, encode
from mpeg4fa.fba.params import FieldCoder, quantise
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.spec import FULL_INTENSITY

FRAME_BITS = 10.0
"""About what a P frame costs beyond its changed fields: the plane header and three segment flushes."""
REPEAT_BITS = 1.0
"""A frame equal to the one before: folded into the previous frame's skip count."""
BEAM = 48
"""States kept per frame: enough for the few ways of writing a frame that differ in what they hold."""

State = tuple[int, ...]


@dataclass(frozen=True)
class _Model:
    """One field's P model: ``symbol[d + FULL_INTENSITY]`` is the symbol coding a change ``d`` (the
    codec's quantiser applied, clipped to the model), ``size`` the number of symbols."""

    symbol: list[int]
    size: int
    qstep: int = 0
    """The field's quantiser step (0: not quantised): a change is priced between the two values as the
    decoder rebuilds them (closed loop: the previous value is already a multiple of the step)."""


def field_models(fap: int, fap_quant: int) -> list[_Model]:
    """The P models of FAP ``fap``'s fields after an intra frame at ``fap_quant``, as the codec sets them up."""
    coder = FieldCoder(fap)
    coder.start_intra(fap_quant)
    changes = np.arange(-FULL_INTENSITY, FULL_INTENSITY + 1)
    out = []
    for j in range(len(coder.fields)):
        size = int(coder.psize[j])
        symbol = quantise(changes, np.int64(coder.qstep[j])) - int(coder.pmin[j])
        out.append(_Model(np.clip(symbol, 0, size - 1).tolist(), size, int(coder.qstep[j])))
    return out


_REBUILT: dict[int, list[int]] = {}


def _rebuilt(value: int, step: int) -> int:
    """``value`` (0..63) as a decoder rebuilds it at quantiser ``step`` (the nearest multiple, as the codec rounds)."""
    if step not in _REBUILT:
        _REBUILT[step] = (quantise(np.arange(FULL_INTENSITY + 1), np.int64(step)) * step).tolist()
    return _REBUILT[step][value]


def _cheapest(n: int, start: State, options: Callable[[int, State], Iterable[State]],
              models: Sequence[_Model]) -> list[State]:
    """The sequence of states (one per frame) of least cost under adaptive ``models``; ties keep the first option.

    Hypotheses that reach the same state merge (the cheaper one's models are kept), as in a Viterbi
    search, and only the :data:`BEAM` cheapest states go on to the next frame.
    """
    counts = tuple(np.ones(m.size) for m in models)
    frames: list[dict[State, tuple[float, State | None]]] = []
    # a hypothesis: its cost, its models' counts, and how many changes it coded (each adds 1 to every model's
    # counts, so a model's total is its size plus that: exactly what summing the counts gives, without the sum)
    current: dict[State, tuple[float, tuple[np.ndarray, ...], int]] = {start: (0.0, counts, 0)}
    for k in range(n):
        nxt: dict[State, tuple[float, State, tuple[np.ndarray, ...], int]] = {}
        for prev, (cost, held, changes) in current.items():
            for cand in options(k, prev):
                grown, coded = held, changes
                if cand == prev:
                    step = REPEAT_BITS
                else:
                    step, grown, coded = FRAME_BITS, [], changes + 1
                    for m, c, a, b in zip(models, held, cand, prev):
                        if m.qstep:
                            a, b = _rebuilt(a, m.qstep), _rebuilt(b, m.qstep)
                        symbol = m.symbol[a - b + FULL_INTENSITY]
                        step -= math.log2(c[symbol] / (m.size + changes))
                        c = c.copy()
                        c[symbol] += 1.0
                        grown.append(c)
                total = cost + step
                if cand not in nxt or total < nxt[cand][0]:
                    nxt[cand] = (total, prev, tuple(grown), coded)
        if len(nxt) > BEAM:
            nxt = dict(sorted(nxt.items(), key=lambda item: item[1][0])[:BEAM])
        frames.append({state: (total, prev) for state, (total, prev, _, _) in nxt.items()})
        current = {state: (total, grown, coded) for state, (total, _, grown, coded) in nxt.items()}
    state = min(current, key=lambda s: current[s][0])
    path = [state]
    for k in range(n - 1, 0, -1):
        state = frames[k][state][1]
        path.append(state)
    return path[::-1]


def compact_visemes(viseme: np.ndarray, fap_quant: int = 3) -> np.ndarray:
    """FAP 1 rows ``(n, 4)`` rewritten to show the same mixtures in the fields cheapest to code.

    A row showing one viseme ``x`` may be ``(x, any, 63)``, ``(any, x, 0)`` or ``(x, x, any)``, "any"
    repeating the previous value; a two-viseme row ``(a, b, w)`` may also be ``(b, a, 63 - w)``.
    ``viseme_def`` (column 3) is kept as is.
    """
    rows = np.asarray(viseme)
    n = len(rows)
    if n == 0:
        return rows.copy()
    s1, s2, blend = (rows[:, j].astype(np.int64) for j in range(3))
    full = FULL_INTENSITY

    def options(k: int, prev: State) -> list[State]:
        a, b, w = int(s1[k]), int(s2[k]), int(blend[k])
        if a == b or w >= full or w <= 0:
            x = b if (w <= 0 and a != b) else a
            return [(x, prev[1], full), (prev[0], x, 0), (x, x, prev[2])]
        return [(a, b, w), (b, a, full - w)]

    path = _cheapest(n, (0, 0, 0), options, field_models(1, fap_quant))
    out = rows.copy()
    out[:, :3] = np.array(path, dtype=out.dtype)
    return out


def compact_expressions(expression: np.ndarray, fap_quant: int = 3) -> np.ndarray:
    """FAP 2 rows ``(n, 6)`` rewritten to show the same expression mixtures in the fields cheapest to code.

    A slot ``(select, intensity)`` with intensity 0 or select 0 (neutral, an all-zero profile) shows
    nothing, whatever the other field holds; the two slots add, so they may swap. ``init_face`` and
    ``expression_def`` (columns 4, 5) are kept as is.
    """
    rows = np.asarray(expression)
    n = len(rows)
    if n == 0:
        return rows.copy()
    fields = rows[:, :4].astype(np.int64)

    def empty(prev_slot: tuple[int, int]) -> list[tuple[int, int]]:
        s, i = prev_slot
        return [prev_slot] if s == 0 or i == 0 else [(s, 0), (0, i)]

    def options(k: int, prev: State) -> list[State]:
        shown = [(int(fields[k, 0]), int(fields[k, 1])), (int(fields[k, 2]), int(fields[k, 3]))]
        shown = [slot for slot in shown if slot[0] != 0 and slot[1] != 0]
        slots = ((prev[0], prev[1]), (prev[2], prev[3]))
        out: list[State] = []
        if len(shown) == 2:
            for first, second in (shown, shown[::-1]):
                out.append(first + second)
        elif len(shown) == 1:
            for one in empty(slots[1]):
                out.append(shown[0] + one)
            for one in empty(slots[0]):
                out.append(one + shown[0])
        else:
            out.extend(a + b for a in empty(slots[0]) for b in empty(slots[1]))
        return out

    path = _cheapest(n, (0, 0, 0, 0), options, field_models(2, fap_quant))
    out = rows.copy()
    out[:, :4] = np.array(path, dtype=out.dtype)
    return out


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` of each run of True."""
    padded = np.r_[False, flags, False].astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def expression_masks(expression: np.ndarray, gaps: Sequence[int] = (0, 12, 25, 50)) -> list[np.ndarray]:
    """Candidate per-frame FAP 2 masks that keep every frame's expression: each sends FAP 2 at least
    where its fields change (before the first sent frame the decoder holds all zeros, neutral).

    Runs of change closer than a gap are joined (a mask change costs an intra frame), and each
    set of runs is also tried reaching back to frame 0 and on to the end (no mask change there).
    The last candidate sends FAP 2 in every frame; an empty list means FAP 2 is never needed.
    """
    rows = np.asarray(expression)[:, :4]
    n = len(rows)
    changes = np.r_[(rows[:1] != 0).any(axis=1), (rows[1:] != rows[:-1]).any(axis=1)] if n else np.zeros(0, bool)
    if not changes.any():
        return []
    masks: list[np.ndarray] = []
    seen: set[bytes] = set()

    def add(mask: np.ndarray) -> None:
        key = np.packbits(mask).tobytes()
        if key not in seen:
            seen.add(key)
            masks.append(mask)

    runs = _runs(changes)
    for gap in gaps:
        joined = [list(runs[0])]
        for a, b in runs[1:]:
            if a - joined[-1][1] <= gap:
                joined[-1][1] = b
            else:
                joined.append([a, b])
        for from_start in (False, True):
            for to_end in (False, True):
                mask = np.zeros(n, dtype=bool)
                for a, b in joined:
                    mask[a:b] = True
                if from_start:
                    mask[:joined[0][1]] = True
                if to_end:
                    mask[joined[-1][0]:] = True
                add(mask)
    add(np.ones(n, dtype=bool))
    return masks


def with_expression_mask(stream: FapStream, expression: np.ndarray, mask: np.ndarray) -> FapStream:
    """``stream`` sending FAP 2 ``expression`` in the frames of ``mask`` (rows not sent are zero, as
    a decoder reads them back), everything else as it is."""
    out = stream.copy()
    out.fap_mask[:, 1] = mask
    out.expression[:] = np.where(mask[:, None], expression, 0)
    return out


def plan_expression_mask(stream: FapStream, expression: np.ndarray, options: EncodeOptions) -> FapStream:
    """The stream with FAP 2 sent in the frames that encode smallest under ``options`` (see
    :func:`expression_masks`); FAP 2 is left out of the mask when no frame needs it."""
    masks = expression_masks(expression)
    if not masks:
        return with_expression_mask(stream, expression, np.zeros(len(stream), dtype=bool))
    trials = [with_expression_mask(stream, expression, mask) for mask in masks]
    sizes = [len(encode(trial, options)) for trial in trials]
    return trials[int(np.argmin(sizes))]
