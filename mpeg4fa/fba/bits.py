"""Bit reader and writer, start codes and next_start_code() stuffing.

Bits are held unpacked (one byte per bit) so that the arithmetic decoder's inner
loop is a plain index into a bytes object. A reader over a file keeps only a
window of the stream, so memory stays flat however long the stream is.
"""
from __future__ import annotations

from typing import BinaryIO

import numpy as np

from .errors import FbaError

START_CODE_PREFIX = 0x000001
_DIGITS = bytes.maketrans(b"\x00\x01", b"01")
"""Unpacked bits (bytes 0 and 1) as the digits '0' and '1', so a field reads with one int(..., 2)."""
_KEEP_BEHIND = 256  # bits kept before the read position when the window slides (rewinds are <= 14)


def truncated(what: str, n: int, left: int) -> str:
    """The message for a field the stream ends inside (both decoder paths word it so)."""
    return f"stream ends inside {what} (needs {n} bits, {left} left)"


def bad_stuffing(bits: int, nbits: int) -> str:
    """The message for next_start_code() stuffing that is not a '0' then '1's."""
    return (f"stuffing bits {bits:0{nbits}b} before a start code should be "
            f"{(1 << (nbits - 1)) - 1:0{nbits}b} (a '0' then '1's)")


def unpack(data: bytes) -> bytes:
    """One byte (0 or 1) per bit, most significant bit first."""
    return np.unpackbits(np.frombuffer(data, dtype=np.uint8)).tobytes()


class BitReader:
    """Reads bits MSB-first from bytes or a binary file; every fault is an :class:`FbaError`."""

    def __init__(self, source: bytes | bytearray | memoryview | BinaryIO, chunk_bytes: int = 1 << 16) -> None:
        if isinstance(source, (bytes, bytearray, memoryview)):
            self._file = None
            self.buf = unpack(bytes(source))
        else:
            self._file = source
            # read1: what has arrived, up to a chunk (a buffered file's read(n) waits for all n bytes,
            # so a live socket opened with makefile('rb') would decode nothing until it closed)
            self._read = getattr(source, "read1", None) or source.read
            self.buf = b""
        self._chunk = chunk_bytes
        self.base = 0  # absolute bit offset of buf[0]
        self.p = 0     # read index into buf

    # ---- position -----------------------------------------------------------------
    @property
    def pos(self) -> int:
        """Absolute bit offset of the next bit to read."""
        return self.base + self.p

    def more(self) -> bool:
        """Load the next chunk of a file source; False at the end of the data."""
        if self._file is None:
            return False
        data = self._read(self._chunk)
        if not data:
            self._file = None
            return False
        drop = max(0, self.p - _KEEP_BEHIND)
        self.buf = self.buf[drop:] + unpack(data)
        self.base += drop
        self.p -= drop
        return True

    def available(self, n: int) -> bool:
        """True when ``n`` more bits can be read."""
        while self.p + n > len(self.buf):
            if not self.more():
                return False
        return True

    def require(self, n: int, what: str) -> None:
        if not self.available(n):
            raise FbaError(truncated(what, n, len(self.buf) - self.p), self.pos)

    def read(self, n: int, what: str = "a field") -> int:
        """Read an ``n``-bit unsigned field."""
        self.require(n, what)
        p = self.p
        self.p = p + n
        return int(self.buf[p:p + n].translate(_DIGITS), 2) if n else 0

    def digits(self, n: int) -> bytes:
        """The next ``n`` bits as ASCII '0'/'1' digits (consumed; the caller made sure they are there)."""
        p = self.p
        self.p = p + n
        return self.buf[p:p + n].translate(_DIGITS)

    def rewind(self, n: int) -> None:
        if n > self.p:
            raise FbaError("cannot rewind before the kept window", self.pos)
        self.p -= n

    # ---- start codes --------------------------------------------------------------
    @property
    def aligned(self) -> bool:
        return self.pos % 8 == 0

    def peek_start_code(self) -> tuple[int, int] | None:
        """The start code at the next byte boundary, as (code, stuffing bits before it), or None.

        The visage decoder always skips to the *next* boundary (a whole byte when
        already aligned, where next_start_code() writes 0x7F); a stream with no
        stuffing byte before an aligned start code is accepted too, because no plane
        can begin with 23 zero bits.
        """
        candidates = [(8 - self.pos % 8)]
        if self.aligned:
            candidates.insert(0, 0)
        for skip in candidates:
            if not self.available(skip + 32):
                continue
            word = 0
            for i in range(self.p + skip, self.p + skip + 32):
                word = (word << 1) | self.buf[i]
            if word >> 8 == START_CODE_PREFIX:
                return word, skip
        return None

    def skip_stuffing(self, nbits: int) -> None:
        """Consume next_start_code() stuffing: a '0' then '1's (0x7F when a whole byte)."""
        if nbits == 0:
            return
        start = self.pos
        bits = self.read(nbits, "next_start_code() stuffing")
        if bits != (1 << (nbits - 1)) - 1:
            raise FbaError(bad_stuffing(bits, nbits), start)


class BitWriter:
    """Collects bits MSB-first; ``getvalue()`` packs them into bytes."""

    def __init__(self) -> None:
        self.buf = bytearray()

    @property
    def pos(self) -> int:
        return len(self.buf)

    def write(self, n: int, value: int) -> None:
        if value < 0 or value >> n:
            raise FbaError(f"{value} does not fit in {n} bits", self.pos)
        self.buf.extend((value >> (n - 1 - i)) & 1 for i in range(n))

    def next_start_code(self) -> None:
        """Stuff to the next byte boundary: '0' then '1's, a whole 0x7F byte when aligned."""
        n = 8 - self.pos % 8
        self.write(n, (1 << (n - 1)) - 1)

    def start_code(self, code: int) -> None:
        self.write(32, code)

    def truncate(self, pos: int) -> None:
        del self.buf[pos:]

    def getvalue(self) -> bytes:
        if self.pos % 8:
            raise FbaError("the stream does not end on a byte boundary", self.pos)
        return np.packbits(np.frombuffer(bytes(self.buf), dtype=np.uint8)).tobytes()
