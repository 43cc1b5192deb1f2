"""The speech layer's exception and warning types."""
from __future__ import annotations

from mpeg4fa.errors import MpegFaError, MpegFaWarning


class MarkupError(MpegFaError, ValueError):
    """Tagged text that cannot be read; says where (line:column, both 1-based) and what to write.

    ``where`` is ``source:line:column``; ``str()`` reads ``source:line:column: message (hint)``.
    """

    def __init__(self, message: str, line: int, column: int, hint: str = "", source: str = "<text>") -> None:
        self.message, self.line, self.column, self.hint, self.source = message, line, column, hint, source
        ValueError.__init__(self, message)

    @property  # type: ignore[override]
    def where(self) -> str:
        """``source:line:column``, computed so that a caller may rename the source after the fact."""
        return f"{self.source}:{self.line}:{self.column}"

    def __reduce__(self):
        return (type(self), (self.message, self.line, self.column, self.hint, self.source))


class TTSError(MpegFaError, RuntimeError):
    """A speech engine that cannot be loaded or cannot speak the text (``where``: the engine)."""


class PhonemeWarning(MpegFaWarning):
    """Phonemes with symbols no table knows, shown by the nearest viseme by features (said once per encode)."""


class MarkupWarning(MpegFaWarning):
    """Malformed tags spoken as text under ``lenient`` (said once, naming the first and the count)."""
