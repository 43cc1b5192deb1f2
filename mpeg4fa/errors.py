"""What every layer's exceptions and warnings share: a message, the thing at fault, and what to do.

:class:`MpegFaError` is the one base: the codec's ``FbaError``, the formats' and
FDP's ``FormatError``/``FdpError``, the face's, the renderer's, the speech
layer's and the CLI's errors all derive from it, so a caller (and the CLI)
catches one type. Each sets ``where`` (the file, bit offset, line:column, FAP or
frame at fault) and ``hint`` (what to do); subclasses may render ``str()`` their
own way but always name the place.
"""
from __future__ import annotations


class MpegFaError(Exception):
    """Base of every error this package raises on bad input or an impossible request.

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


_OS_WORDS: dict[type, tuple[tuple[str, str], tuple[str, str]]] = {
    FileNotFoundError: (("no such file", "check the path and the current directory"),
                        ("cannot write it: no such folder, or one that takes no files",
                         "write it into an existing folder")),
    IsADirectoryError: (("is a directory, not a file", "name a file inside it"),
                        ("is a directory, not a file", "give a file name")),
    PermissionError: (("permission denied", "check the file's permissions"),
                      ("cannot write it: permission denied", "check the folder's permissions, or write elsewhere")),
}
"""Per OS error: (what a reader says, what a writer says), each (the problem, what to do)."""


def _os_words(exc: OSError, writing: bool) -> tuple[str, str]:
    for kind, words in _OS_WORDS.items():
        if isinstance(exc, kind):
            return words[writing]
    return f"cannot {'write it' if writing else 'read the file'}: {exc.strerror or exc}", ""


def unwritable(exc: OSError) -> tuple[str, str]:
    """What a writer says when the system will not take a file: the problem and what to do (the caller names the
    file), worded for an output (a reader's "no such file, check the path" misleads there)."""
    return _os_words(exc, writing=True)


def unreadable(exc: OSError) -> tuple[str, str]:
    """What a reader says when the system will not give it a file: the problem and what to do, in the
    same words for every reader (the caller names the file)."""
    return _os_words(exc, writing=False)
