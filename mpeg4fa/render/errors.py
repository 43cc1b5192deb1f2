"""The render layer's exception and warning types."""
from __future__ import annotations


class RenderError(RuntimeError):
    """Rendering, audio or video output that cannot be carried out.

    ``where`` names the thing at fault (a file, a frame index, the GL context)
    and ``hint`` says what to do about it.
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


class RenderWarning(UserWarning):
    """Something was adjusted to go on (audio padded or trimmed, frames dropped): said, not fatal."""
