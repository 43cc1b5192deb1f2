"""The speech layer's exception types."""
from __future__ import annotations

from mpeg4fa.errors import MpegFaError


class MarkupError(ValueError):
    """Tagged text that cannot be read; says where (line:column, both 1-based) and what to write."""

    def __init__(self, message: str, line: int, column: int, hint: str = "", source: str = "<text>") -> None:
        self.message, self.line, self.column, self.hint, self.source = message, line, column, hint, source
        super().__init__(message)

    def __str__(self) -> str:
        text = f"{self.source}:{self.line}:{self.column}: {self.message}"
        return f"{text} ({self.hint})" if self.hint else text

    def __reduce__(self):
        return (type(self), (self.message, self.line, self.column, self.hint, self.source))


class TTSError(MpegFaError, RuntimeError):
    """A speech engine that cannot be loaded or cannot speak the text (``where``: the engine)."""
