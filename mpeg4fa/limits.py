"""What an option's value may be: the ranges that the CLI, a batch manifest and the library all check.

Why one module, below every layer: ``--aa`` means the same in ``play``, ``say`` and a batch
manifest, and a program calling ``Renderer(samples=3)`` must be refused as the command line
is, with one line naming the value and what is allowed, not a GL error (or an OverflowError
for ``1e308``) from deep inside. The CLI's argparse types (:mod:`mpeg4fa.cli.options`) and the
manifest reader (:mod:`mpeg4fa.batch.manifest`) are built on these. A rule that belongs to one
layer stays in it and is called there (the frame rates a stream carries:
:meth:`mpeg4fa.fba.stream.FrameRate.from_fps`).
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from mpeg4fa.errors import MpegFaError


class LimitError(MpegFaError, ValueError):
    """A value outside what the code can do: ``where`` names the option, the message the value, ``hint`` the range."""


@dataclass(frozen=True)
class Limit:
    """A number in ``low..high`` (bounds included, either may be open), whole or not, or one of ``choices``."""

    what: str
    low: float | None = None
    high: float | None = None
    whole: bool = False
    choices: tuple[int, ...] = ()

    def allowed(self) -> str:
        """The allowed values: ``16..8192``, ``0, 1, 2, 4, 8 or 16``, ``>= 0``."""
        if self.choices:
            return ", ".join(map(str, self.choices[:-1])) + f" or {self.choices[-1]}"
        low, high = (self._bound(b) for b in (self.low, self.high))
        if low is not None and high is not None:
            return f"{low}..{high}"
        if low is not None:
            return f">= {low}"
        return f"<= {high}" if high is not None else "any finite number"

    def _bound(self, bound: float | None) -> str | None:
        if bound is None:
            return None
        return str(int(bound)) if self.whole or float(bound).is_integer() else f"{bound:g}"

    def check(self, value: object, where: str | None = None) -> int | float:
        """``value`` if allowed (as int for a whole number), else LimitError naming it."""
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise LimitError(f"{self.what} {value!r} is not a number", where, hint=self.allowed())
        number = int(value) if isinstance(value, numbers.Integral) else float(value)
        shown = _shown(number)
        if isinstance(number, float) and not math.isfinite(number):
            raise LimitError(f"{self.what} {shown} is not a finite number", where, hint=self.allowed())
        if self.whole or self.choices:
            if isinstance(number, float) and not number.is_integer():
                raise LimitError(f"{self.what} {shown} is not a whole number", where, hint=self.allowed())
        if self.choices and number not in self.choices:
            raise LimitError(f"{self.what} {shown} is not one of {self.allowed()}", where)
        if (self.low is not None and number < self.low) or (self.high is not None and number > self.high):
            raise LimitError(f"{self.what} {shown} is out of range: give {self.allowed()}", where)
        return int(number) if self.whole or self.choices else number

    def parse(self, text: str, where: str | None = None) -> int | float:
        """The value written in ``text`` (a command-line argument, a CSV cell), checked."""
        stripped = text.strip()
        try:
            value: int | float = int(stripped) if self.whole or self.choices else float(stripped)
        except ValueError:
            if stripped.lstrip("+-").isdigit():  # int()'s 4,300-digit limit
                raise LimitError(f"{self.what} {_short(stripped)} is out of range: give {self.allowed()}",
                                 where) from None
            kind = "a whole number" if self.whole or self.choices else "a number"
            raise LimitError(f"{_short(text)!r} is not {kind}", where, hint=self.allowed()) from None
        return self.check(value, where)


def _shown(number: int | float) -> str:
    text = f"{number:g}" if isinstance(number, float) else str(number)
    return _short(text)


def _short(text: str) -> str:
    return text if len(text) <= 24 else text[:24] + "..."


SIDE = Limit("image side", 16, 8192, whole=True)
"""Pixels on a side of what the commands render or bake (the renderer itself draws 1 to 8192)."""
SAMPLES = Limit("anti-aliasing samples", whole=True, choices=(0, 1, 2, 4, 8, 16))
"""MSAA samples: 0 (off) or a power of two (what OpenGL multisampling takes); the GL context may allow fewer
(Mesa's llvmpipe: 4), and the renderer says so."""
CRF = Limit("crf", 0, 51, whole=True)
"""H.264 constant rate factor (libx264's range)."""
QUANT = Limit("quantiser", 0, 31, whole=True)
"""fap_quant / bap_quant: the intra header's 5-bit field."""
PORT = Limit("port", 1, 65535, whole=True)
"""A TCP port."""
WORKERS = Limit("workers", 1, 1024, whole=True)
"""Worker processes of a local batch cluster."""


def parse_size(text: str, where: str | None = None) -> tuple[int, int]:
    """An image size written ``W`` (square) or ``WxH``, each side within :data:`SIDE`."""
    parts = text.strip().lower().split("x")
    if not 1 <= len(parts) <= 2 or not all(p.strip().isdigit() for p in parts):
        raise LimitError(f"{_short(text)!r}: expected W or WxH", where,
                         hint=f"each side {SIDE.allowed()} pixels, e.g. 512 or 640x480")
    try:
        sides = [SIDE.parse(p, where) for p in parts]
    except LimitError as exc:
        raise LimitError(f"{_short(text)!r}: {exc.message}", where, hint="e.g. 512 or 640x480") from None
    width, height = (sides * 2)[:2]
    return int(width), int(height)
