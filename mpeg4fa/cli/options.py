"""The checks every command's option values go through: argparse ``type=`` functions, one per kind of value.

Why one set: ``--fps`` means the same in ``encode``, ``say`` and ``play``, so it is read and
checked in one place. A value that is not a number, not finite or out of range is an argparse
error (one line, exit status 2) before any work starts.
"""
from __future__ import annotations

import argparse
import math
from typing import Any, Callable, Protocol


class Commands(Protocol):
    """What ``ArgumentParser.add_subparsers()`` returns, as far as the commands' ``register`` functions use it."""

    def add_parser(self, name: str, **kwargs: Any) -> argparse.ArgumentParser: ...


def _whole(text: str) -> int:
    try:
        return int(text.strip())
    except ValueError:  # also the digit limit of a 5000-digit number
        raise argparse.ArgumentTypeError(f"{_short(text)!r} is not a whole number") from None


def _real(text: str) -> float:
    try:
        value = float(text.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"{_short(text)!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{_short(text)!r} is not a finite number")
    return value


def _short(text: str) -> str:
    return text if len(text) <= 24 else text[:24] + "..."


def _check_range(value: float, shown: str, low: float | None, high: float | None) -> None:
    """ArgumentTypeError unless ``low <= value <= high`` (either bound may be open-ended)."""
    if (low is not None and value < low) or (high is not None and value > high):
        span = f"{low:g}..{high:g}" if low is not None and high is not None else (
            f">= {low:g}" if low is not None else f"<= {high:g}")
        raise argparse.ArgumentTypeError(f"{shown} is out of range: give {span}")


def integer(low: int | None = None, high: int | None = None) -> Callable[[str], int]:
    """A whole number in ``low..high`` (either bound may be open-ended)."""
    def parse(text: str) -> int:
        value = _whole(text)
        _check_range(value, str(value), low, high)
        return value
    parse.__name__ = "integer"
    return parse


def real(low: float | None = None, high: float | None = None) -> Callable[[str], float]:
    """A finite number in ``low..high`` (bounds included; either may be open-ended)."""
    def parse(text: str) -> float:
        value = _real(text)
        _check_range(value, text.strip(), low, high)
        return value
    parse.__name__ = "number"
    return parse


def fps(text: str) -> float:
    """A frame rate the FBA bitstream can carry (the codec's own rule: ``FrameRate.from_fps``)."""
    from ..errors import MpegFaError
    from ..fba.stream import FrameRate

    value = _real(text)
    try:
        FrameRate.from_fps(value)
    except (ValueError, MpegFaError) as exc:
        raise argparse.ArgumentTypeError(getattr(exc, "message", None) or str(exc)) from None
    return value


def size(text: str) -> tuple[int, int]:
    """An image size ``W`` or ``WxH``, each side 16..8192 pixels."""
    try:
        parts = [int(v) for v in text.lower().split("x")]
    except ValueError:
        parts = []
    if len(parts) == 1:
        parts *= 2
    if len(parts) != 2 or min(parts) < SIDE[0] or max(parts) > SIDE[1]:
        raise argparse.ArgumentTypeError(f"{_short(text)!r}: expected W or WxH, {SIDE[0]} to {SIDE[1]}, "
                                         "e.g. 512 or 640x480")
    return parts[0], parts[1]


def speech_rate(text: str) -> int:
    """Words per minute within what espeak-ng accepts (every engine is held to it: a rate of 1 makes hours)."""
    from ..speech.tts.espeak import RATE_RANGE

    return integer(*RATE_RANGE)(text)


def mask_types(text: str) -> list[int]:
    """The 10 FAP group mask types, comma-separated, each 0..3."""
    try:
        types = [int(t) for t in text.split(",")]
    except ValueError:
        types = []
    from ..spec import N_FAP_GROUPS

    if len(types) != N_FAP_GROUPS or any(t not in (0, 1, 2, 3) for t in types):
        raise argparse.ArgumentTypeError(f"give {N_FAP_GROUPS} comma-separated mask types, each 0..3")
    return types


SIDE = (16, 8192)
"""Smallest and largest image side the commands render or bake."""
quant = integer(0, 31)
"""fap_quant / bap_quant: the 5-bit quantiser field."""
period = integer(0)
"""A count of frames such as --intra-period (0 = only the first)."""
side = integer(*SIDE)
"""A square image's side in pixels."""
samples = integer(0, 16)
"""Anti-aliasing (MSAA) samples; the GL context may allow fewer, and says so."""
crf = integer(0, 51)
"""H.264 constant rate factor."""
frame = integer()
"""A frame index (negative counts from the end)."""
seconds = real(0.0)
"""A time in seconds from the start."""
finite = real()
"""Any finite number."""
