"""The one exception type of the formats layer.

Every reader and writer in :mod:`mpeg4fa.formats` reports bad input as a
:class:`FormatError` that points at the offending spot, so that a user can open
the file at ``path:line:column`` and fix it, and callers need to catch only one
type (it is a :class:`ValueError`, so ``except ValueError`` works too).
"""
from __future__ import annotations


class FormatError(ValueError):
    """A file (or the data about to be written to one) breaks its format.

    ``line`` and ``column`` are 1-based; ``column`` is ``None`` when the problem
    belongs to a whole line or to the end of the file. ``str()`` reads
    ``path:line:column: problem (hint)``, the form compilers use, so editors and
    terminals can jump to the spot.
    """

    def __init__(self, path: str, line: int, column: int | None, problem: str, hint: str = "") -> None:
        self.path = path
        self.line = line
        self.column = column
        self.problem = problem
        self.hint = hint
        super().__init__(self._render())

    def _render(self) -> str:
        where = f"{self.path}:{self.line}" if self.column is None else f"{self.path}:{self.line}:{self.column}"
        return f"{where}: {self.problem} ({self.hint})" if self.hint else f"{where}: {self.problem}"

    def __reduce__(self):  # keep the attributes when pickled (e.g. across processes)
        return (type(self), (self.path, self.line, self.column, self.problem, self.hint))
