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
from array import array
from collections.abc import Callable, Hashable, Sequence
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


_SYMBOLS: dict[tuple[tuple[int, ...], int], list[list[int]]] = {}


def _symbols(model: _Model) -> list[list[int]]:
    """``table[a][b]``: the symbol coding a move from ``b`` to ``a`` (0..63 each) under ``model``, the
    quantiser's rebuilding applied to both ends (one lookup in the search's inner loop; a coarse step
    may rebuild 63 a little past it, a change then priced as the largest the model holds). Made once
    per model: text is coded chunk by chunk, each chunk a search of its own."""
    key = (tuple(model.symbol), model.qstep)
    if key not in _SYMBOLS:
        _SYMBOLS[key] = _symbol_table(model)
    return _SYMBOLS[key]


def _symbol_table(model: _Model) -> list[list[int]]:
    values = range(FULL_INTENSITY + 1)
    rebuilt = [_rebuilt(v, model.qstep) if model.qstep else v for v in values]
    last = len(model.symbol) - 1
    return [[model.symbol[min(max(rebuilt[a] - rebuilt[b] + FULL_INTENSITY, 0), last)] for b in values]
            for a in values]


def _cheapest(keys: Sequence[Hashable], start: State, options: Callable[[Hashable, State], list[State]],
              models: Sequence[_Model]) -> list[State]:
    """The sequence of states (one per frame) of least cost under adaptive ``models``; ties keep the first option.

    ``options(keys[k], prev)``: the states frame ``k`` may take after ``prev`` (asked once per distinct pair).
    Hypotheses that reach the same state merge (the cheaper one's models are kept), as in a Viterbi
    search, and only the :data:`BEAM` cheapest states go on to the next frame.

    Why it is fast (linear in frames, a few microseconds per hypothesis): a candidate is priced from its
    parent's counts as they are, and only the survivors of a frame get counts of their own (copied, one added
    per coded symbol); and a move costs at least :data:`FRAME_BITS`, so a move into a state that is already
    held, and may stay as it is for :data:`REPEAT_BITS`, is not priced when that stay is cheaper than the
    move could be (its place among the candidates is kept, so ties and order are as if it were priced).
    """
    tables = [_symbols(m) for m in models]
    sizes = [m.size for m in models]
    choices: dict[Hashable, dict[State, list[State]]] = {}  # options(key, prev), by key, then by prev
    stays: dict[Hashable, dict[State, bool]] = {}  # whether a state is among its own options, by key
    # per frame: the states kept and each one's parent as an index into the frame before's (about 0.5 kB a frame:
    # a dict a frame took 2.3 kB, 120 MB for the 51,000 frames of 10,000 characters spoken in memory)
    kept: list[tuple[State, ...]] = []
    parents: list[array] = []
    before: dict[State, int] = {start: 0}
    # a hypothesis: its cost, its models' counts (lists of ints: counts start at one, one added per symbol),
    # and how many changes it coded (each adds 1 to every model's counts, so a model's total is its size plus
    # that: exactly what summing the counts gives, without the sum)
    current: dict[State, tuple[float, tuple[list[int], ...], int]] = {start: (0.0, tuple([1] * s for s in sizes), 0)}
    log2, never = math.log2, math.inf
    for key in keys:
        known = choices.get(key)
        if known is None:
            known, stays[key] = choices.setdefault(key, {}), {}
        stay_known = stays[key]
        # a candidate: its cost, its parent state, the parent's counts, its change count, the symbols it codes
        nxt: dict[State, tuple[float, State, tuple[list[int], ...], int, list[int] | None]] = {}
        for prev, (cost, held, changes) in current.items():
            cands = known.get(prev)
            if cands is None:
                cands = known[prev] = list(options(key, prev))
            floor = cost + FRAME_BITS
            for cand in cands:
                if cand == prev:
                    total, symbols, coded = cost + REPEAT_BITS, None, changes
                else:
                    there = current.get(cand)
                    if there is not None and floor > there[0] + REPEAT_BITS:
                        stay = stay_known.get(cand)
                        if stay is None:
                            own = known.get(cand)
                            if own is None:
                                own = known[cand] = list(options(key, cand))
                            stay = stay_known[cand] = cand in own
                        if stay:  # the stay wins: keep the candidate's place, never its price
                            if cand not in nxt:
                                nxt[cand] = (never, prev, held, changes, None)
                            continue
                    step, symbols, coded = FRAME_BITS, [], changes + 1
                    for table, size, c, a, b in zip(tables, sizes, held, cand, prev):
                        symbol = table[a][b]
                        step -= log2(c[symbol] / (size + changes))
                        symbols.append(symbol)
                    total = cost + step
                if cand not in nxt or total < nxt[cand][0]:
                    nxt[cand] = (total, prev, held, coded, symbols)
        if len(nxt) > BEAM:
            nxt = dict(sorted(nxt.items(), key=lambda item: item[1][0])[:BEAM])
        kept.append(tuple(nxt))
        parents.append(array("H", [before[prev] for _, prev, _, _, _ in nxt.values()]))
        before = {state: i for i, state in enumerate(kept[-1])}
        current = {}
        for state, (total, _, held, coded, symbols) in nxt.items():
            if symbols is not None:
                grown = []
                for c, symbol in zip(held, symbols):
                    c = c.copy()
                    c[symbol] += 1
                    grown.append(c)
                held = tuple(grown)
            current[state] = (total, held, coded)
    state = min(current, key=lambda s: current[s][0])
    index = kept[-1].index(state)
    path = [state]
    for k in range(len(keys) - 1, 0, -1):
        index = parents[k][index]
        path.append(kept[k - 1][index])
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
    full = FULL_INTENSITY

    def options(row: State, prev: State) -> list[State]:
        a, b, w = row
        if a == b or w >= full or w <= 0:
            x = b if (w <= 0 and a != b) else a
            return [(x, prev[1], full), (prev[0], x, 0), (x, x, prev[2])]
        return [(a, b, w), (b, a, full - w)]

    keys = [tuple(row) for row in rows[:, :3].astype(np.int64).tolist()]
    path = _cheapest(keys, (0, 0, 0), options, field_models(1, fap_quant))
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

    def empty(prev_slot: tuple[int, int]) -> list[tuple[int, int]]:
        s, i = prev_slot
        return [prev_slot] if s == 0 or i == 0 else [(s, 0), (0, i)]

    def options(row: State, prev: State) -> list[State]:
        shown = [row[:2], row[2:]]
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

    keys = [tuple(row) for row in rows[:, :4].astype(np.int64).tolist()]
    path = _cheapest(keys, (0, 0, 0, 0), options, field_models(2, fap_quant))
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
