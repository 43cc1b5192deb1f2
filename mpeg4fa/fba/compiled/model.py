"""Adaptive frequency models as Fenwick trees over flat arrays (the compiled path's model search).

The reference (:class:`mpeg4fa.fba.arith.AdaptiveModel`) keeps a cumulative table, finds a
symbol by binary search and adapts in O(n); real ranges reach 3,721 symbols (a FAP with step 1
and range code 31), so here each model is a Fenwick (binary indexed) tree over its counts:
search and update in O(log n), identical symbols. All models of a part share three arrays:

* ``freq[foff + s]``: count of symbol ``s`` (every count starts at 1);
* ``tree[toff + j]``, ``j = 1..n``: the Fenwick sums of those counts (``tree[toff]`` unused);
* ``total[m]``: the model's total count (``cum[0]`` of the reference).
"""
from __future__ import annotations

import numpy as np

from . import jit

MAX_FREQUENCY = 16383
"""A model whose total reaches this halves every count before counting the next symbol (SYNTAX.md 9)."""


@jit
def build(freq, foff, tree, toff, n):
    """Fenwick sums of ``freq[foff:foff+n]`` into ``tree[toff+1:toff+n+1]`` in O(n)."""
    for j in range(1, n + 1):
        tree[toff + j] = freq[foff + j - 1]
    for j in range(1, n + 1):
        k = j + (j & -j)
        if k <= n:
            tree[toff + k] += tree[toff + j]


@jit
def prefix(tree, toff, i):
    """Sum of the counts of symbols ``0..i-1``."""
    s = 0
    while i > 0:
        s += tree[toff + i]
        i -= i & -i
    return s


@jit
def find(tree, toff, n, top, t):
    """The symbol ``s`` with ``prefix(s) < t <= prefix(s + 1)``, and ``prefix(s)``.

    ``top`` is the largest power of two <= n. Counts are positive, so prefixes strictly grow.
    """
    pos = 0
    rem = t
    step = top
    while step:
        nxt = pos + step
        if nxt <= n and tree[toff + nxt] < rem:
            pos = nxt
            rem -= tree[toff + nxt]
        step >>= 1
    return pos, t - rem


@jit
def count(freq, foff, tree, toff, n, total, m, s):
    """Count symbol ``s`` in model ``m``; first halve every count when the total reached 16383."""
    if total[m] == MAX_FREQUENCY:
        t = 0
        for j in range(n):
            f = (freq[foff + j] + 1) // 2
            freq[foff + j] = f
            t += f
        total[m] = t
        build(freq, foff, tree, toff, n)
    freq[foff + s] += 1
    total[m] += 1
    j = s + 1
    while j <= n:
        tree[toff + j] += 1
        j += j & -j


def highest_power_of_two(n: int) -> int:
    """The largest power of two <= n (n >= 1): where :func:`find` starts its walk."""
    return 1 << (int(n).bit_length() - 1)


def uniform_bank(sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Fresh models of the given sizes (every count 1): ``foff``, ``toff``, ``freq``, ``tree``, ``total``."""
    sizes = np.asarray(sizes, dtype=np.int64)
    foff = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64) if len(sizes) else np.zeros(0, np.int64)
    toff = foff + np.arange(len(sizes), dtype=np.int64)  # each tree takes n + 1 slots
    freq = np.ones(int(sizes.sum()), dtype=np.int64)
    tree = np.zeros(int(sizes.sum()) + len(sizes), dtype=np.int64)
    for m, n in enumerate(sizes.tolist()):  # a uniform tree: tree[j] = lowbit(j)
        j = np.arange(1, n + 1)
        tree[toff[m] + j] = j & -j
    return foff, toff, freq, tree, sizes.copy()
