"""The coders' state laid out for the kernels: model tables, Fenwick banks, one array of predictions.

Both compiled drivers (:mod:`mpeg4fa.fba.fastpath` for decoding, :mod:`mpeg4fa.fba.encoder` for
encoding) let the reference code read or write intra planes, which set up the
:class:`~mpeg4fa.fba.params.ValueCoder`/:class:`~mpeg4fa.fba.params.FieldCoder` objects, and then
turn those coders into what :mod:`.kernels` works on for the P planes that follow.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.fba.params import FieldCoder, ValueCoder
from mpeg4fa.fba.stream import N_FAPS

from . import kernels as k

PREV_BASE = {k.VISEME: 0, k.EXPRESSION: 3, k.FAP: 7}
"""Where each face coder's previous values sit in the face's one prediction array."""
FACE_PREDICTIONS = 3 + 4 + N_FAPS


@dataclass
class Bank:
    """One part's P models as the kernels read them."""

    meta: np.ndarray
    total: np.ndarray
    freq: np.ndarray
    tree: np.ndarray

    @classmethod
    def empty(cls) -> "Bank":
        z = np.zeros(0, dtype=np.int64)
        return cls(np.zeros((0, k.META_COLUMNS), dtype=np.int64), z, z.copy(), z.copy())


def share_face_predictions(viseme: FieldCoder, expression: FieldCoder, faps: ValueCoder) -> np.ndarray:
    """One array holding the three face coders' previous values; the coders keep views of it, so the
    reference code (intra planes) and the kernels (P planes) predict from the same numbers."""
    prev = np.zeros(FACE_PREDICTIONS, dtype=np.int64)
    viseme.prev, expression.prev, faps.prev = prev[0:3], prev[3:7], prev[7:]
    return prev


def _rows(bank: int, coder: FieldCoder | ValueCoder, prev_base: int) -> np.ndarray:
    """Model-table rows (columns: see :mod:`.kernels`) for the P models of ``coder``'s masked parameters."""
    n = len(coder.idx)
    meta = np.zeros((n, k.META_COLUMNS), dtype=np.int64)
    meta[:, k.BANK] = bank
    meta[:, k.COL] = coder.idx
    meta[:, k.PREV] = prev_base + np.asarray(coder.idx, dtype=np.int64)
    meta[:, k.QSTEP] = coder.qstep
    meta[:, k.PMIN] = coder.pmin
    meta[:, k.SIZE] = coder.psize
    meta[:, k.TOPSTEP] = k.highest_power_of_two(meta[:, k.SIZE])
    meta[:, k.SELMAX] = [coder.select_max(j) for j in range(n)] if isinstance(coder, FieldCoder) else -1
    return meta


def _bank(meta: np.ndarray) -> Bank:
    foff, toff, freq, tree, total = k.uniform_bank(meta[:, k.SIZE])
    meta[:, k.FOFF], meta[:, k.TOFF] = foff, toff
    return Bank(meta, total, freq, tree)


def face_bank(viseme: FieldCoder, expression: FieldCoder, faps: ValueCoder, mask: np.ndarray) -> Bank:
    """Fresh P models of the face after an intra header with FAP ``mask``: FAP 1 fields, FAP 2 fields, FAPs."""
    parts = []
    if mask[0]:
        parts.append(_rows(k.VISEME, viseme, PREV_BASE[k.VISEME]))
    if mask[1]:
        parts.append(_rows(k.EXPRESSION, expression, PREV_BASE[k.EXPRESSION]))
    parts.append(_rows(k.FAP, faps, PREV_BASE[k.FAP]))
    return _bank(np.concatenate(parts))


def body_bank(baps: ValueCoder) -> Bank:
    """Fresh P models of the body after an intra header."""
    return _bank(_rows(k.BAP, baps, 0))


def coder_of(row: np.ndarray, viseme: FieldCoder, expression: FieldCoder, faps: ValueCoder,
             baps: ValueCoder) -> tuple[FieldCoder | ValueCoder, int]:
    """The coder a model-table row belongs to, and the row's index among that coder's parameters."""
    coder = {k.VISEME: viseme, k.EXPRESSION: expression, k.FAP: faps, k.BAP: baps}[int(row[k.BANK])]
    return coder, int(np.flatnonzero(np.asarray(coder.idx) == row[k.COL])[0])
