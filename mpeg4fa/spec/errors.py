"""The tables layer's exception: a request the standard's tables cannot answer.

A viseme or expression code that names nothing, a blend or intensity out of its
range: these come from streams and files, so they are located errors
(:class:`~mpeg4fa.errors.MpegFaError`, ``where`` = the frame) that the CLI prints as
one line, not bare ``ValueError`` tracebacks. A broken data file in ``spec/`` is
a different matter (a bug in the package) and stays a plain ``ValueError``.
"""
from __future__ import annotations

from mpeg4fa.errors import MpegFaError


class SpecError(MpegFaError, ValueError):
    """FAP 1/FAP 2 fields (or a viseme, expression or set name) outside what the tables define.

    ``where`` is the frame (``"frame 12"``) when the fields came from a stream's arrays.
    """
