"""The face layer's one exception type."""
from __future__ import annotations

from mpeg4fa.errors import WhereHintError


class FaceError(WhereHintError, ValueError):
    """A face model, calibration or animation request that cannot be carried out.

    ``where`` names the thing at fault (a feature point label, a FAP number, a
    frame index, a cache path) so that the message says what to fix.
    """
