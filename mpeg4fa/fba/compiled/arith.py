"""The adaptive arithmetic decoder of one segment, on unpacked bits and Fenwick models.

Step for step the reference's :func:`mpeg4fa.fba.arith.decode_segment` (``spec/SYNTAX.md`` 9):
16 bits of look-ahead, one symbol per model, a stuffed '1' dropped after 22 zeros, 14 bits
given back at the end. Symbols go straight to values (level = symbol + P min, times the
quantiser step, plus the previous value: SYNTAX.md 8), since P planes are all this path decodes.
"""
from __future__ import annotations

from . import jit
from .model import count, find

TOP, Q1, Q2, Q3 = 65535, 16384, 32768, 49152
MAX_ZERO_RUN = 22
REWIND_BITS = 14
END_OF_DATA, BAD_STUFFING = -1, -2
"""Error results of :func:`segment`: the bits ran out, or a '0' stood where a stuffed '1' must."""

# columns of a model table (one row per model, in coding order)
BANK, COL, PREV, QSTEP, PMIN, SIZE, FOFF, TOFF, TOPSTEP, SELMAX = range(10)
META_COLUMNS = 10
VISEME, EXPRESSION, FAP, BAP = range(4)


@jit
def _bit(buf, p, nbuf, zeros):
    """(bit, p, zeros): the next bit, skipping a stuffed '1'; bit END_OF_DATA / BAD_STUFFING on a fault."""
    while True:
        if p >= nbuf:
            return END_OF_DATA, p, zeros
        bit = buf[p]
        p += 1
        if zeros == MAX_ZERO_RUN:
            if bit == 0:
                return BAD_STUFFING, p, zeros
            zeros = 0
            continue
        zeros = zeros + 1 if bit == 0 else 0
        return bit, p, zeros


@jit
def segment(buf, p, nbuf, meta, lo, hi, total, freq, tree, prev, values):
    """Decode models ``lo..hi-1`` of ``meta`` from ``buf[p:]``; return (position after the rewind, 0)
    or (fault position, END_OF_DATA / BAD_STUFFING). Values land in ``prev`` and ``values[m - lo]``."""
    zeros = 0
    code = 0
    for _ in range(16):
        bit, p, zeros = _bit(buf, p, nbuf, zeros)
        if bit < 0:
            return p, bit
        code = (code << 1) | bit
    low = 0
    high = TOP
    for m in range(lo, hi):
        n = meta[m, SIZE]
        foff = meta[m, FOFF]
        toff = meta[m, TOFF]
        t = total[m]
        length = high - low + 1
        target = ((code - low + 1) * t - 1) // length
        s, before = find(tree, toff, n, meta[m, TOPSTEP], t - target)
        cum_hi = t - before
        cum_lo = cum_hi - freq[foff + s]
        high = low - 1 + (length * cum_hi) // t
        low = low + (length * cum_lo) // t
        while True:
            if high < Q2:
                pass
            elif low >= Q2:
                code -= Q2
                low -= Q2
                high -= Q2
            elif low >= Q1 and high < Q3:
                code -= Q1
                low -= Q1
                high -= Q1
            else:
                break
            low <<= 1
            high = (high << 1) | 1
            bit, p, zeros = _bit(buf, p, nbuf, zeros)
            if bit < 0:
                return p, bit
            code = (code << 1) | bit
        count(freq, foff, tree, toff, n, total, m, s)
        level = s + meta[m, PMIN]
        q = meta[m, QSTEP]
        value = prev[meta[m, PREV]] + (level * q if q != 0 else level)
        prev[meta[m, PREV]] = value
        values[m - lo] = value
    return p - REWIND_BITS, 0
