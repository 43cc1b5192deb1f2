"""The one exception type of the formats layer.

Every reader and writer in :mod:`mpeg4fa.formats` reports bad input as a
:class:`FormatError` that points at the offending spot, so that a user can open
the file at ``path:line:column`` and fix it, and callers need to catch only one
type (it is a :class:`~mpeg4fa.errors.MpegFaError` and a :class:`ValueError`).
"""
from __future__ import annotations

from mpeg4fa.errors import MpegFaError, MpegFaWarning, unreadable


class FormatError(MpegFaError, ValueError):
    """A file (or the data about to be written to one) breaks its format.

    ``line`` and ``column`` are 1-based; ``column`` is ``None`` when the problem
    belongs to a whole line or to the end of the file; both are ``None`` for a
    fault of the file as a whole (missing, a directory). ``str()`` reads
    ``path:line:column: problem (hint)``, the form compilers use, so editors and
    terminals can jump to the spot; ``where`` is its ``path:line:column`` part and
    ``message`` the problem.
    """

    def __init__(self, path: str, line: int | None, column: int | None, problem: str, hint: str = "") -> None:
        self.path = path
        self.line = line
        self.column = column
        self.problem = problem
        self.hint = hint
        ValueError.__init__(self, problem)

    @classmethod
    def no_place(cls, path: str, problem: str, hint: str = "") -> "FormatError":
        """An error about the file as a whole (missing, unreadable, not text); renders as ``path: problem``."""
        return cls(path, None, None, problem, hint)

    @classmethod
    def from_os_error(cls, path: str, exc: OSError) -> "FormatError":
        """A file that cannot be opened or read, said plainly and naming the file (a writer uses
        :func:`mpeg4fa.errors.unwritable`'s words)."""
        return cls.no_place(path, *unreadable(exc))

    @property
    def message(self) -> str:  # type: ignore[override]
        """The problem, without the place (the base class's name for it)."""
        return self.problem

    @property  # type: ignore[override]
    def where(self) -> str:
        """``path:line:column`` (or less, when the line or column is unknown)."""
        if self.line is None:
            return self.path
        return f"{self.path}:{self.line}" if self.column is None else f"{self.path}:{self.line}:{self.column}"

    def _render(self) -> str:
        return f"{self.where}: {self.problem} ({self.hint})" if self.hint else f"{self.where}: {self.problem}"

    def __str__(self) -> str:
        return self._render()

    def __reduce__(self):  # keep the attributes when pickled (e.g. across processes)
        return (type(self), (self.path, self.line, self.column, self.problem, self.hint))


class FormatWarning(MpegFaWarning):
    """Something a file format cannot hold was left out (e.g. BAPs written to a .fap): said, not fatal."""
