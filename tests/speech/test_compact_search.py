"""The beam search of mpeg4fa.speech.compact chooses exactly what pricing every candidate would choose.

The search skips the pricing of moves that cannot win and copies the models' counts only for the states it
keeps (fuzz text:37087@0: 1,200 characters of tagged Mandarin, 7,081 frames, took 9 s in the search alone).
Here a plain beam search, every candidate priced from its own copy of the counts, is the reference: both
must give the same fields, ties included, on rows shaped like speech (long runs, one or two visemes or
expressions, empty slots) and on random ones.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mpeg4fa.speech import compact
from mpeg4fa.speech.compact import BEAM, FRAME_BITS, REPEAT_BITS, compact_expressions, compact_visemes


def _plain_cheapest(keys, start, options, models):
    """Every candidate priced from a copy of its parent's counts; the first of equal costs kept."""
    hyps = {start: (0.0, [[1.0] * m.size for m in models], 0)}
    back = []
    for key in keys:
        nxt = {}
        for prev, (cost, counts, changes) in hyps.items():
            for cand in options(key, prev):
                if cand == prev:
                    total, grown, coded = cost + REPEAT_BITS, counts, changes
                else:
                    step, grown, coded = FRAME_BITS, [], changes + 1
                    for m, c, a, b in zip(models, counts, cand, prev):
                        if m.qstep:
                            a, b = compact._rebuilt(a, m.qstep), compact._rebuilt(b, m.qstep)
                        symbol = m.symbol[a - b + 63]
                        step -= math.log2(c[symbol] / (m.size + changes))
                        c = list(c)
                        c[symbol] += 1.0
                        grown.append(c)
                    total = cost + step
                if cand not in nxt or total < nxt[cand][0]:
                    nxt[cand] = (total, prev, grown, coded)
        if len(nxt) > BEAM:
            nxt = dict(sorted(nxt.items(), key=lambda item: item[1][0])[:BEAM])
        back.append({state: prev for state, (_, prev, _, _) in nxt.items()})
        hyps = {state: (total, grown, coded) for state, (total, _, grown, coded) in nxt.items()}
    state = min(hyps, key=lambda s: hyps[s][0])
    path = [state]
    for k in range(len(keys) - 1, 0, -1):
        state = back[k][state]
        path.append(state)
    return path[::-1]


def _speech_like(rng, kind: str) -> np.ndarray:
    """Rows in runs, as text gives them: FAP 2 with one held expression and changes, FAP 1 with moves."""
    n = int(rng.integers(5, 25))
    if kind == "expression":
        select = rng.integers(0, int(rng.integers(2, 7)), size=(n, 2)) * (rng.random((n, 2)) < rng.random())
        intensity = rng.choice([0, 21, 42, 63, int(rng.integers(0, 64))], size=(n, 2))
        rows = np.c_[select[:, 0], intensity[:, 0], select[:, 1], intensity[:, 1], np.zeros((n, 2))]
    else:
        select = rng.integers(0, int(rng.integers(2, 15)), size=(n, 2))
        rows = np.c_[select, rng.choice([0, 63, 30, int(rng.integers(0, 64))], size=n), np.zeros(n)]
    return np.repeat(rows.astype(np.int64), rng.integers(1, 20, size=n), axis=0)


@pytest.mark.parametrize("seed", range(2))
def test_the_search_chooses_as_pricing_every_candidate_would(monkeypatch, seed):
    rng = np.random.default_rng(seed)
    cases = [("expression", _speech_like(rng, "expression")) for _ in range(8)]
    cases += [("viseme", _speech_like(rng, "viseme")) for _ in range(8)]
    fast = [compact_expressions(rows) if kind == "expression" else compact_visemes(rows) for kind, rows in cases]
    monkeypatch.setattr(compact, "_cheapest", _plain_cheapest)
    for (kind, rows), got in zip(cases, fast):
        want = compact_expressions(rows) if kind == "expression" else compact_visemes(rows)
        assert np.array_equal(got, want), (kind, len(rows))


def test_a_held_expression_prices_few_moves(monkeypatch):
    """One expression held over a long text (the fuzz case's shape): the moves that cannot beat staying are not
    priced, so the work per frame stays small; the choice is the reference's."""
    rows = np.zeros((1200, 6), dtype=np.int64)
    rows[:, :2] = (1, 47)
    rows[500:700, 2:4] = (3, 21)
    priced = []
    real_log2 = math.log2
    monkeypatch.setattr(compact.math, "log2", lambda x: priced.append(1) or real_log2(x))
    got = compact_expressions(rows)
    monkeypatch.setattr(compact.math, "log2", real_log2)
    assert len(priced) < 4 * len(rows) * 4  # four fields: fewer than four priced moves a frame on average
    monkeypatch.setattr(compact, "_cheapest", _plain_cheapest)
    assert np.array_equal(got, compact_expressions(rows))


def test_a_coarse_quantiser_is_priced_not_refused():
    """fap_quant 5 rebuilds 63 as 65: the change is priced as the largest the model holds (an IndexError before)."""
    rows = np.array([[1, 63, 0, 0, 0, 0], [1, 63, 0, 0, 0, 0], [2, 63, 0, 0, 0, 0]] * 4, dtype=np.int64)
    out = compact_expressions(rows, fap_quant=5)
    assert out.shape == rows.shape
