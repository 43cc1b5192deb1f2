"""What the decoder-output layer raises and says."""
from __future__ import annotations

from mpeg4fa.errors import MpegFaError, MpegFaWarning


class FapValueError(MpegFaError, ValueError):
    """FAP values no rule can turn into a face: a wrong shape, a non-finite value, a FAP that is
    not low-level. ``where`` names the FAP (and frame) at fault."""


class ClampWarning(MpegFaWarning):
    """A value no face can show was clamped to one it can (see :mod:`.limits`): said, not fatal."""
