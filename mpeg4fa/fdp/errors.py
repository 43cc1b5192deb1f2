"""The FDP layer's one exception type.

Every reader in :mod:`mpeg4fa.fdp` reports bad content as an :class:`FdpError`
that points at the spot to fix: ``path:line:column`` for the text forms (JSON,
Xface XML) and ``path: byte N`` for the binary stream. It is a
:class:`~mpeg4fa.formats.errors.FormatError` (and so a ``ValueError``), so callers
that already catch the formats layer's error catch this one too.
"""
from __future__ import annotations

import os
from pathlib import Path

from mpeg4fa.formats.errors import FormatError


class FdpError(FormatError):
    """An FDP file (or value about to be written) that breaks its format.

    Text forms set ``line`` and ``column`` (1-based); the binary form sets
    ``offset`` (0-based byte offset from the first byte of the stream) and leaves
    ``line``/``column`` None. A fault with no place in the content (a missing
    file) has all three None and renders as ``path: problem (hint)``.
    """

    def __init__(self, path: str, line: int | None, column: int | None, problem: str, hint: str = "",
                 offset: int | None = None) -> None:
        self.offset = offset
        super().__init__(path, line, column, problem, hint)  # type: ignore[arg-type]

    @classmethod
    def at_byte(cls, path: str, offset: int, problem: str, hint: str = "") -> "FdpError":
        """An error in a binary stream at byte ``offset``."""
        return cls(path, None, None, problem, hint, offset)

    @classmethod
    def no_place(cls, path: str, problem: str, hint: str = "") -> "FdpError":
        """An error about the file as a whole (unreadable, unrecognised)."""
        return cls(path, None, None, problem, hint)

    @classmethod
    def from_os_error(cls, path: str, exc: OSError) -> "FdpError":
        """A file that cannot be opened, read or written, said plainly."""
        if isinstance(exc, FileNotFoundError):
            return cls.no_place(path, "no such file", "check the path and the current directory")
        if isinstance(exc, IsADirectoryError):
            return cls.no_place(path, "is a directory, not a file", "name the FDP file inside it")
        if isinstance(exc, PermissionError):
            return cls.no_place(path, "permission denied", "check the file's permissions")
        return cls.no_place(path, f"cannot access the file: {exc.strerror or exc}")

    def _render(self) -> str:
        if self.offset is not None:
            where = f"{self.path}: byte {self.offset}"
        elif self.line is None:
            where = self.path
        elif self.column is None:
            where = f"{self.path}:{self.line}"
        else:
            where = f"{self.path}:{self.line}:{self.column}"
        return f"{where}: {self.problem} ({self.hint})" if self.hint else f"{where}: {self.problem}"

    def __reduce__(self):  # keep every attribute when pickled
        return (type(self), (self.path, self.line, self.column, self.problem, self.hint, self.offset))


def read_bytes(path: "str | os.PathLike[str]") -> bytes:
    """The file's bytes; a missing or unreadable file becomes an :class:`FdpError` naming it."""
    try:
        return Path(path).read_bytes()
    except OSError as exc:
        raise FdpError.from_os_error(str(path), exc) from None
