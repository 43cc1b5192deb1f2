"""The 16-bit adaptive arithmetic coder of FAP/BAP planes (H.263 Annex E style SAC).

A *segment* is one run of arithmetic-coded symbols: the decoder resets, reads 16
bits ahead, decodes the symbols and finally moves back 14 bits, because the
encoder's flush wrote only 2 (+ pending) bits of the 16 the decoder looked ahead.
Inside a segment the encoder stuffs a '1' after 22 consecutive '0's so that no
start code can appear; the decoder drops it.

Models keep a descending cumulative frequency table ``cum`` (``cum[0]`` = total,
``cum[n]`` = 0). Intra models are used once per intra frame and never adapt, so
they are uniform and need no table: a plain ``int`` (the alphabet size) stands
for one. Adaptive (P) models are :class:`AdaptiveModel`, which stores ``-cum`` so
that numpy's ``searchsorted`` finds a symbol in one call.
"""
from __future__ import annotations

from typing import Sequence, Union

import numpy as np

from .bits import BitReader, BitWriter
from .errors import FbaError

TOP = 65535
Q1 = 16384
Q2 = 32768
Q3 = 49152
MAX_FREQUENCY = 16383
MAX_ZERO_RUN = 22
REWIND_BITS = 14
SEGMENT_ENDS = "stream ends inside an arithmetic-coded segment"
STUFFING_EXPECTED = "stuffing '1' expected after 22 zero bits"


class AdaptiveModel:
    """An adaptive frequency model over ``n`` symbols, all counts starting at 1."""

    __slots__ = ("n", "neg")

    def __init__(self, n: int) -> None:
        self.n = n
        self.neg = np.arange(-n, 1, dtype=np.int64)  # neg[j] = -cum[j] = j - n

    def update(self, symbol: int) -> None:
        """Count ``symbol``; halve every count first when the total reached 16383."""
        neg = self.neg
        if neg[0] == -MAX_FREQUENCY:
            cum = -neg
            freq = (cum[:-1] - cum[1:] + 1) // 2
            neg[:-1] = -np.cumsum(freq[::-1])[::-1]
        neg[: symbol + 1] -= 1

    def cum(self) -> np.ndarray:
        return -self.neg


Model = Union[int, AdaptiveModel]


def decode_segment(reader: BitReader, models: Sequence[Model], adapt: bool) -> list[int]:
    """Decode one symbol per model (see the module docstring); return the symbols."""
    buf, p, nbuf = reader.buf, reader.p, len(reader.buf)
    zerorun = 0

    def next_bit() -> int:
        """One bit, dropping the stuffed '1' that follows 22 zeros.

        It must not call itself: a closure that refers to itself is a reference cycle,
        which would keep every old reader window alive until the cycle collector runs.
        """
        nonlocal buf, p, nbuf, zerorun
        while True:
            if p >= nbuf:
                reader.p = p
                if not reader.available(1):
                    raise FbaError(SEGMENT_ENDS, reader.pos)
                buf, p, nbuf = reader.buf, reader.p, len(reader.buf)
            bit = buf[p]
            p += 1
            if zerorun == MAX_ZERO_RUN:
                if not bit:
                    raise FbaError(STUFFING_EXPECTED, reader.base + p - 1)
                zerorun = 0
                continue  # the stuffed '1' carries no information
            zerorun = zerorun + 1 if bit == 0 else 0
            return bit

    code = 0
    for _ in range(16):
        code = (code << 1) | next_bit()

    low, high = 0, TOP
    symbols = []
    for model in models:
        length = high - low + 1
        if isinstance(model, int):
            total = model
            target = ((code - low + 1) * total - 1) // length
            i = total - target
            cum_hi, cum_lo = total - i + 1, total - i
        else:
            neg = model.neg
            total = -int(neg[0])
            target = ((code - low + 1) * total - 1) // length
            i = int(neg.searchsorted(-target))
            cum_hi, cum_lo = -int(neg[i - 1]), -int(neg[i])
        high = low - 1 + (length * cum_hi) // total
        low = low + (length * cum_lo) // total
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
            code = (code << 1) | next_bit()
        symbol = i - 1
        if adapt and not isinstance(model, int):
            model.update(symbol)
        symbols.append(symbol)
    reader.p = p - REWIND_BITS
    return symbols


class SegmentEnd:
    """Where an encoded segment ended and how many '0's it ended with.

    The decoder keeps counting zeros through its 14-bit look-ahead while the
    encoder has reset its count, so a segment that ends in 8 or more zeros may
    meet the following bits as stuffing; the encoder checks these places.
    """

    __slots__ = ("pos", "zeros")

    def __init__(self, pos: int, zeros: int) -> None:
        self.pos = pos
        self.zeros = zeros


def encode_segment(writer: BitWriter, symbols: Sequence[int], models: Sequence[Model], adapt: bool) -> SegmentEnd:
    """Encode one symbol per model and flush; return where the segment ended."""
    out = writer.buf
    low, high = 0, TOP
    pending = 0
    zerorun = 0

    def emit(bit: int) -> None:
        nonlocal zerorun, pending
        for b in (bit,) + (1 - bit,) * pending:
            if zerorun == MAX_ZERO_RUN:
                out.append(1)
                zerorun = 0
            out.append(b)
            zerorun = zerorun + 1 if b == 0 else 0
        pending = 0

    for symbol, model in zip(symbols, models):
        length = high - low + 1
        if isinstance(model, int):
            total = model
            cum_hi, cum_lo = total - symbol, total - symbol - 1
        else:
            neg = model.neg
            total = -int(neg[0])
            cum_hi, cum_lo = -int(neg[symbol]), -int(neg[symbol + 1])
        high = low - 1 + (length * cum_hi) // total
        low = low + (length * cum_lo) // total
        while True:
            if high < Q2:
                emit(0)
            elif low >= Q2:
                emit(1)
                low -= Q2
                high -= Q2
            elif low >= Q1 and high < Q3:
                pending += 1
                low -= Q1
                high -= Q1
            else:
                break
            low <<= 1
            high = (high << 1) | 1
        if adapt and not isinstance(model, int):
            model.update(symbol)
    pending += 1
    emit(0 if low < Q1 else 1)
    return SegmentEnd(len(out), zerorun)


def lookahead_desyncs(bits: bytes | bytearray, end: SegmentEnd) -> bool:
    """True when a decoder's 14-bit look-ahead after ``end`` would drop or reject a bit as stuffing."""
    run, i, counted = end.zeros, end.pos, 0
    while counted < REWIND_BITS:
        if i >= len(bits):
            return True
        bit = bits[i]
        i += 1
        if run == MAX_ZERO_RUN:
            return True  # a '0' is an error, a '1' is dropped: either way the decoder loses sync
        run = run + 1 if bit == 0 else 0
        counted += 1
    return False
