"""The conformance layer's error: a suite, manifest or decoder protocol that cannot be used."""
from __future__ import annotations

from mpeg4fa.errors import MpegFaError


class ConformanceError(MpegFaError, ValueError):
    """A manifest, vector, expected file or decoder output that breaks the suite's format (``where``: the file)."""
