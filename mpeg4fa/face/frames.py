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
  sent overrides the high-level value of that FAP.
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.fba.stream import FapStream
from mpeg4fa.spec import FAP_BY_NAME, FAP_GROUP, FAPS, N_FAPS, expand_high_level


def _counterparts() -> np.ndarray:
    """``(68, 2)`` columns of each FAP's interpolation partners: left/right first, then
    inner/outer lip (-1: none)."""
    partner = np.full((N_FAPS, 2), -1)
    for record in FAPS:
        for a, b in (("_l_", "_r_"), ("_r_", "_l_"), ("_lm", "_rm"), ("_rm", "_lm")):
            if a in record.name:
                other = FAP_BY_NAME.get(record.name.replace(a, b))
                if other is not None:
                    partner[record.number - 1, 0] = other.number - 1
    for inner in range(4, 14):
        partner[inner - 1, 1], partner[inner + 47 - 1, 1] = inner + 47 - 1, inner - 1
    return partner


PARTNERS = _counterparts()


def _last_sent(mask: np.ndarray) -> np.ndarray:
    """Index of the last frame at or before each frame where the column was sent (-1: never)."""
    n = len(mask)
    idx = np.where(mask, np.arange(n)[:, None], -1)
    return np.maximum.accumulate(idx, axis=0)


def _mask_types(stream: FapStream) -> np.ndarray:
    """``(n, 68)`` mask type governing each FAP at each frame (from the latest intra header)."""
    n = stream.n_frames
    per_frame = np.ones((n, N_FAPS), dtype=np.int8)
    group_of = np.asarray(FAP_GROUP) - 1
    for start in sorted(stream.intra):
        face = stream.intra[start].face
        if face is not None:
            per_frame[start:] = np.asarray(face.mask_types, dtype=np.int8)[group_of]
    return per_frame


def resolve(stream: FapStream) -> np.ndarray:
    """``(n, 68)`` float FAP values to show at each frame (columns 0/1 stay 0)."""
    n = stream.n_frames
    mask = stream.fap_mask.astype(bool)
    values = stream.fap_values.astype(np.float64)
    if n == 0:
        return np.zeros((0, N_FAPS))
    types = _mask_types(stream)
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
    cols = np.arange(N_FAPS)[None, :]
    out = np.where(last >= 0, copied[np.maximum(last, 0), cols], 0.0)

    low_level_known = last >= 0
    low_level_known[:, :2] = False
    if mask[:, :2].any():
        vis_last = _last_sent(mask[:, :1])[:, 0]
        exp_last = _last_sent(mask[:, 1:2])[:, 0]
        viseme = np.where((vis_last >= 0)[:, None], stream.viseme[np.maximum(vis_last, 0)], 0)
        expression = np.where((exp_last >= 0)[:, None], stream.expression[np.maximum(exp_last, 0)], 0)
        high = expand_high_level(viseme, expression)
        out = np.where(low_level_known, out, high)
    out[:, :2] = 0.0
    return out
