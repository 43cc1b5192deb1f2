"""The aligner's error: a recording that cannot be read, is silent, or does not fit its transcript."""
from __future__ import annotations

from mpeg4fa.speech.errors import TTSError


class AlignError(TTSError):
    """A recording and transcript that cannot be aligned; ``where`` names the recording (its file)."""
