"""The checks every command's option values go through: argparse ``type=`` functions, one per kind of value.

Why one set: ``--fps`` means the same in ``encode``, ``say`` and ``play``, so it is read and
checked in one place. A value that is not a number, not finite or out of range is an argparse
error (one line, exit status 2) naming the allowed values, before any work starts. The ranges
are :mod:`mpeg4fa.limits` (shared with the batch manifest and the library), the frame rate is
the codec's own rule (:meth:`mpeg4fa.fba.stream.FrameRate.from_fps`).
"""
from __future__ import annotations

import argparse
from typing import Any, Callable, Protocol

from .. import limits
from ..fba.limits import MAX_SPAN_SECONDS
from ..limits import Limit, LimitError


class Commands(Protocol):
    """What ``ArgumentParser.add_subparsers()`` returns, as far as the commands' ``register`` functions use it."""

    def add_parser(self, name: str, **kwargs: Any) -> argparse.ArgumentParser: ...


def of(limit: Limit) -> Callable[[str], Any]:
    """The argparse type of a :class:`~mpeg4fa.limits.Limit`: its value, or an ArgumentTypeError saying the range."""
    def parse(text: str):
        try:
            return limit.parse(text)
        except LimitError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    parse.__name__ = "integer" if limit.whole or limit.choices else "number"
    return parse


def integer(low: int | None = None, high: int | None = None, what: str = "value") -> Callable[[str], int]:
    """A whole number in ``low..high`` (either bound may be open-ended)."""
    return of(Limit(what, low, high, whole=True))


def real(low: float | None = None, high: float | None = None, what: str = "value") -> Callable[[str], float]:
    """A finite number in ``low..high`` (bounds included; either may be open-ended)."""
    return of(Limit(what, low, high))


def fps(text: str) -> float:
    """A frame rate the FBA bitstream can carry (the codec's own rule: ``FrameRate.from_fps``)."""
    from ..errors import MpegFaError
    from ..fba.stream import FrameRate

    value = of(Limit("frame rate"))(text)
    try:
        FrameRate.from_fps(value)
    except (ValueError, MpegFaError) as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return value


def size(text: str) -> tuple[int, int]:
    """An image size ``W`` or ``WxH``, each side 16..8192 pixels."""
    try:
        return limits.parse_size(text)
    except LimitError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def speech_rate(text: str) -> int:
    """Words per minute within what espeak-ng accepts (every engine is held to it: a rate of 1 makes hours)."""
    from ..speech.tts.espeak import RATE_RANGE

    return integer(*RATE_RANGE, what="speech rate")(text)


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


SIDE = (limits.SIDE.low, limits.SIDE.high)
"""Smallest and largest image side the commands render or bake."""
MOST_FRAMES = MAX_SPAN_SECONDS * 256
"""No stream spans more frames: 24 hours (the codec's bound) at the fastest rate a header carries."""
quant = of(limits.QUANT)
"""fap_quant / bap_quant: the 5-bit quantiser field."""
period = integer(0, MOST_FRAMES, what="intra period")
"""A count of frames such as --intra-period (0 = only the first)."""
side = of(limits.SIDE)
"""A square image's side in pixels."""
samples = of(limits.SAMPLES)
"""Anti-aliasing (MSAA) samples: 0 or a power of two to 16; the GL context may allow fewer, and says so."""
crf = of(limits.CRF)
"""H.264 constant rate factor."""
port = of(limits.PORT)
"""A TCP port for the local servers."""
workers = of(limits.WORKERS)
"""Worker processes of a local batch cluster."""
frame = integer(-MOST_FRAMES, MOST_FRAMES, what="frame")
"""A frame index (negative counts from the end)."""
seconds = real(0.0, float(MAX_SPAN_SECONDS), what="time")
"""A time in seconds from the start (a stream spans at most 24 h)."""
finite = real()
"""Any finite number."""
