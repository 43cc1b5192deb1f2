"""The CLI's own errors: options that do not go together (exit status 2, like argparse's), and command-line
input that names no usable file (exit status 1, like every other bad input)."""
from __future__ import annotations

from ..errors import MpegFaError


class UsageError(MpegFaError):
    """A combination of command-line options that cannot work; ``hint`` names one that does."""


class InputError(MpegFaError):
    """A command-line argument that should name a readable file and does not (``where``: the argument)."""
