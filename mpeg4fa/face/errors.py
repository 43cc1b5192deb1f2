"""The face layer's one exception type."""
from __future__ import annotations


class FaceError(ValueError):
    """A face model, calibration or animation request that cannot be carried out.

    ``where`` names the thing at fault (a feature point label, a FAP number, a
    frame index, a cache path) so that the message says what to fix.
    """

    def __init__(self, message: str, where: str | None = None, hint: str = "") -> None:
        self.message = message
        self.where = where
        self.hint = hint
        super().__init__(message)

    def __str__(self) -> str:
        text = f"{self.where}: {self.message}" if self.where else self.message
        return f"{text} ({self.hint})" if self.hint else text

    def __reduce__(self):
        return (type(self), (self.message, self.where, self.hint))
