"""``mpeg4fa info --trace``: the bit-level syntax trace of a .fba stream, as text or JSON lines."""
from __future__ import annotations

import argparse
import json
import re
import sys
from typing import TextIO

from ..fba import FbaError
from ..fba.trace import Element, trace, value_text, window
from ..formats.sniff import sniff
from .errors import InputError

_FRAMES = re.compile(r"^(\d*)(:?)(\d*)$")


def frame_range(text: str) -> tuple[int, int | None]:
    """``A:B`` -> frames A..B-1; ``A:`` from A on; ``:B`` the first B; ``A`` frame A alone (argparse type)."""
    m = _FRAMES.match(text.strip())
    if not m or not (m.group(1) or m.group(3)):
        raise argparse.ArgumentTypeError(f"{text!r} is not a frame range A:B (A:, :B or one frame A)")
    first = int(m.group(1) or 0)
    stop = int(m.group(3)) if m.group(3) else (None if m.group(2) else first + 1)
    if stop is not None and stop <= first:
        raise argparse.ArgumentTypeError(f"frame range {text!r} is empty (B must be greater than A)")
    return first, stop


def run_trace(args: argparse.Namespace) -> int:
    """Print the elements (of the --frames range), then, at a fault, raise the decoder's error (exit 1)."""
    if sniff(args.stream) != "fba":  # sniff says "fap" of any other file, whose reader says what is wrong
        raise InputError("is not a binary .fba stream: it does not begin with an FBA start code (--trace shows the "
                         "bits of .fba streams; 'mpeg4fa info' without it reads .fap and .bap text files)",
                         str(args.stream))
    first, stop = args.frames or (0, None)
    out = sys.stdout
    emit = _json_line if args.json else _TextLines(out)
    try:
        for element in window(trace(args.stream), first, stop):
            emit(element, out)
    except FbaError as exc:
        if args.json:
            json.dump({"error": exc.message, "bit_offset": exc.bit_offset, "frame": exc.frame}, out)
            out.write("\n")
        out.flush()  # the elements before the error line on stderr
        raise
    return 0


def _json_line(element: Element, out: TextIO) -> None:
    json.dump(element.as_dict(), out)
    out.write("\n")


class _TextLines:
    """One line per element under a column header, a ``-- frame N`` line where each plane begins."""

    def __init__(self, out: TextIO) -> None:
        out.write(f"{'bit':>9} {'width':>5}  {'element':<40} value\n")
        self.frame: int | None = None

    def __call__(self, e: Element, out: TextIO) -> None:
        if e.frame is not None and e.frame != self.frame:
            self.frame = e.frame
            out.write(f"-- frame {e.frame}\n")
        out.write(f"{e.offset:>9} {e.width:>5}  {e.name:<40} {value_text(e)}\n")
