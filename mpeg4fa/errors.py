"""What the layers' exceptions and warnings share: a message, the thing at fault, and what to do about it."""
from __future__ import annotations


class WhereHintError(Exception):
    """Base of errors that name the thing at fault (``where``) and say what to do (``hint``).

    ``str()`` reads ``"where: message (hint)"``; the attributes survive pickling.
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


class MpegFaWarning(UserWarning):
    """Base of the layers' warnings: something was adjusted so that the work could go on.

    The CLI prints each as one ``mpeg4fa COMMAND: warning: ...`` line.
    """
