"""The CLI's own error: options that do not go together (exit status 2, like argparse's)."""
from __future__ import annotations

from ..errors import MpegFaError


class UsageError(MpegFaError):
    """A combination of command-line options that cannot work; ``hint`` names one that does."""
