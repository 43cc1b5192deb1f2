"""The FDP layer's one exception type.

Every reader in :mod:`mpeg4fa.fdp` reports bad content as an :class:`FdpError`
that points at the spot to fix: ``path:line:column`` for the text forms (JSON,
Xface XML) and ``path: byte N`` for the binary stream. It is a
:class:`~mpeg4fa.formats.errors.FormatError` (and so an
:class:`~mpeg4fa.errors.MpegFaError` and a ``ValueError``), so callers that
already catch the formats layer's error catch this one too.
"""
from __future__ import annotations

import os
import stat

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

    @property  # type: ignore[override]
    def where(self) -> str:
        """``path: byte N`` for the binary form, else ``path:line:column`` (or less)."""
        if self.offset is not None:
            return f"{self.path}: byte {self.offset}"
        return super().where

    def __reduce__(self):  # keep every attribute when pickled
        return (type(self), (self.path, self.line, self.column, self.problem, self.hint, self.offset))


MAX_FILE_BYTES = 256 << 20
"""Largest FDP file read (256 MiB): far above any face (a textured mesh of a million vertices is
~60 MB), low enough that a wrong path (a disk image, a device) fails at once instead of filling memory."""


def read_bytes(path: "str | os.PathLike[str]", limit: int | None = None, what: str = "an FDP file") -> bytes:
    """The file's bytes (at most ``limit``, default :data:`MAX_FILE_BYTES`); a missing, unreadable, oversized
    or non-file path becomes an :class:`FdpError` naming it."""
    name = str(path)
    limit = MAX_FILE_BYTES if limit is None else limit
    try:
        with open(path, "rb") as handle:
            info = os.fstat(handle.fileno())
            if not (stat.S_ISREG(info.st_mode) or stat.S_ISFIFO(info.st_mode)):
                raise FdpError.no_place(name, "is not a regular file (a device or socket?)", f"name {what}")
            if info.st_size > limit:
                raise FdpError.no_place(name, f"is {info.st_size:,} bytes, more than {what} may be "
                                        f"({limit:,})", f"is this {what}?")
            data = handle.read(limit + 1)
    except OSError as exc:
        raise FdpError.from_os_error(name, exc) from None
    if len(data) > limit:
        raise FdpError.no_place(name, f"holds more than {limit:,} bytes, more than {what} may be",
                                f"is this {what}?")
    return data
