"""The codec layer's one exception type."""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .stream import FapStream


class FbaError(ValueError):
    """A stream that cannot be decoded (or values that cannot be encoded).

    ``bit_offset`` is where the fault was seen, counted from the first bit of the
    stream; ``frame`` the index of the frame being coded (None before the first).
    ``partial`` holds the frames decoded before the fault, so that nothing decoded
    is lost.
    """

    def __init__(self, message: str, bit_offset: int | None = None, frame: int | None = None,
                 partial: "FapStream | None" = None) -> None:
        self.message = message
        self.bit_offset = bit_offset
        self.frame = frame
        self.partial = partial
        super().__init__(message)

    def __str__(self) -> str:
        return self._describe()

    def _describe(self) -> str:
        where = []
        if self.bit_offset is not None:
            where.append(f"bit {self.bit_offset} (byte {self.bit_offset // 8})")
        if self.frame is not None:
            where.append(f"frame {self.frame}")
        return f"{self.message} at {', '.join(where)}" if where else self.message


class UnsupportedFeature(FbaError):
    """A legal stream that uses a part of the syntax this codec does not implement (DCT mode)."""
