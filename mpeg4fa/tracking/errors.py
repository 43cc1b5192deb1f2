"""The landmarks-and-tracking layer's exception and warning types."""
from __future__ import annotations

from mpeg4fa.errors import MpegFaError, MpegFaWarning
from mpeg4fa.extras import install_line

EXTRA_HINT = f"photo and video input need the track extra: tools/dev.sh test installs it ({install_line('track')})"
"""What to do when the landmark model is not installed: one sentence, the same everywhere."""


class TrackingError(MpegFaError, ValueError):
    """A photo or frame the landmark model cannot work on; ``where`` names the file (and frame)."""


class NoFaceError(TrackingError):
    """The landmark model found no face where one was needed."""


class MissingExtraError(TrackingError):
    """The landmark model (the ``track`` extra) is not installed."""

    def __init__(self, message: str = "the face landmark model (mediapipe) is not installed",
                 where: str | None = None, hint: str = EXTRA_HINT) -> None:
        super().__init__(message, where, hint)


class TrackingWarning(MpegFaWarning):
    """Something was decided to go on (several faces: the largest was taken): said once, not fatal."""
