"""The render layer's exception and warning types."""
from __future__ import annotations

from mpeg4fa.errors import MpegFaWarning, MpegFaError


class RenderError(MpegFaError, RuntimeError):
    """Rendering, audio or video output that cannot be carried out.

    ``where`` names the thing at fault (a file, a frame index, the GL context)
    and ``hint`` says what to do about it.
    """


class RenderWarning(MpegFaWarning):
    """Something was adjusted to go on (audio padded or trimmed, frames dropped): said, not fatal."""
