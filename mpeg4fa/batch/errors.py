"""Errors of batch rendering: a manifest that cannot be run, and where in it the trouble is."""
from __future__ import annotations

from mpeg4fa.errors import MpegFaError


class BatchError(MpegFaError):
    """A manifest that cannot be run; ``problems`` lists every fault found, each with its place.

    All faults are collected before raising (every missing file at once), so that one
    edit of the manifest fixes them all.
    """

    def __init__(self, message: str, where: str | None = None, hint: str = "",
                 problems: tuple[str, ...] = ()) -> None:
        super().__init__(message, where, hint)
        self.problems = tuple(problems)

    def __reduce__(self):
        return (type(self), (self.message, self.where, self.hint, self.problems))
