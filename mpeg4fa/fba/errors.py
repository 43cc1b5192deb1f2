"""The codec layer's one exception type."""
from __future__ import annotations

from typing import TYPE_CHECKING

from mpeg4fa.errors import MpegFaError

if TYPE_CHECKING:
    from .stream import FapStream


class FbaError(MpegFaError, ValueError):
    """A stream that cannot be decoded (or values that cannot be encoded).

    ``bit_offset`` is where the fault was seen, counted from the first bit of the
    stream; ``frame`` the index of the frame being coded (None before the first).
    ``partial`` holds the frames decoded before the fault, so that nothing decoded
    is lost. ``where`` reads ``"bit N (byte M), frame F"`` from the two (they are
    filled in as the error travels up through the decoder, so it is computed);
    ``str()`` reads ``"message at bit N (byte M), frame F"``, then `` (hint)`` if any.
    """

    def __init__(self, message: str, bit_offset: int | None = None, frame: int | None = None,
                 partial: "FapStream | None" = None, hint: str = "") -> None:
        self.message = message
        self.bit_offset = bit_offset
        self.frame = frame
        self.partial = partial
        self.hint = hint
        ValueError.__init__(self, message)

    @property  # type: ignore[override]
    def where(self) -> str | None:
        """The place as text: ``bit N (byte M), frame F`` (either part may be absent)."""
        parts = []
        if self.bit_offset is not None:
            parts.append(f"bit {self.bit_offset} (byte {self.bit_offset // 8})")
        if self.frame is not None:
            parts.append(f"frame {self.frame}")
        return ", ".join(parts) or None

    def __str__(self) -> str:
        return self._describe()

    def _describe(self) -> str:
        where = self.where
        text = f"{self.message} at {where}" if where else self.message
        return f"{text} ({self.hint})" if self.hint else text

    def __reduce__(self):
        return (type(self), (self.message, self.bit_offset, self.frame, self.partial, self.hint))


class UnsupportedFeature(FbaError):
    """A legal stream that uses a part of the syntax this codec does not implement (DCT mode)."""
