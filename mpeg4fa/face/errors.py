"""The face layer's exception and warning types."""
from __future__ import annotations

from mpeg4fa.decoded.errors import ClampWarning
from mpeg4fa.errors import MpegFaError


class FaceError(MpegFaError, ValueError):
    """A face model, calibration or animation request that cannot be carried out.

    ``where`` names the thing at fault (a feature point label, a FAP number, a
    frame index, a cache path) so that the message says what to fix.
    """


FaceWarning = ClampWarning
"""A value a face cannot show was clamped to one it can: the decoder output's warning
(:mod:`mpeg4fa.decoded.limits`), named here for the face's users."""
