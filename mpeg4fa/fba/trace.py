"""A bit-level syntax trace: every element of an FBA stream with its bit offset, width and value.

Why it is built this way: the trace runs the reference decoder itself
(:class:`~mpeg4fa.fba.decoder._Decoder`) with the header syntax read through
:class:`~mpeg4fa.fba.syntax.Tracing` and its segments reported by the decoder's
``decoded`` hook, so it cannot disagree with the decoder about any field, width or
value: what is listed is what was decoded. The elements tile the stream: each starts
where the one before ended, from bit 0 to the end of the end code (then, if the file
goes on, one ``trailing`` element the decoder never reads).

It reads bits with the project's :class:`~mpeg4fa.fba.bits.BitReader`, not
``bitstring``: the trace needs the decoder's reads, not a second reader of its own
(see ``tools/bench_bits.py`` and the README for the measurements).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Iterator

import numpy as np

from . import syntax
from .bits import BitReader
from .decoder import Source, _Decoder, _guarded, _opened
from .errors import FbaError
from .params import FieldCoder, ValueCoder
from .stream import END_CODE, OBJECT_START_CODE_OLD, PLANE_START_CODE_OLD

KINDS = ("start_code", "stuffing", "field", "marker", "segment", "trailing")
"""What an element is: a 32-bit start code, next_start_code() stuffing, a fixed-width header field
(flags and raw bits such as viseme_def included), a marker bit, an arithmetic-coded segment, or
bits after the end code that the decoder does not read."""

SEGMENT_NAMES = {"viseme": "FAP 1 (viseme) segment", "expression": "FAP 2 (expression) segment",
                 "face": "FAP segment", "body": "BAP segment"}


def start_code_name(code: int) -> str:
    """The syntax name of a start code value (the old 0x101/0x103 codes are named so)."""
    if code == END_CODE:
        return "fba_object_end_code"
    if code == OBJECT_START_CODE_OLD:
        return "fba_object_start_code (old 0x101)"
    if code == PLANE_START_CODE_OLD:
        return "fba_object_plane_start_code (old 0x103)"
    return "fba_object_start_code" if code & 0xFF == 0xBA else "fba_object_plane_start_code"


@dataclass(frozen=True)
class Element:
    """One syntax element: where it is (``offset``, ``width`` in bits), what it is and what it read.

    ``frame`` is the plane it belongs to (a plane start code belongs to the plane it starts),
    None for the object start code, the end code and trailing bits. A segment's ``value`` holds
    its reconstructed values, ``symbols`` the arithmetic-coded symbols and ``labels`` what each
    value is (``"FAP 3"``, ``"FAP 1 viseme_select1"``); ``intra`` says whether its models were
    the intra (uniform) ones or the adaptive P ones.
    """

    offset: int
    width: int
    kind: str
    name: str
    value: int | tuple[int, ...] | None
    frame: int | None
    symbols: tuple[int, ...] = field(default=())
    labels: tuple[str, ...] = field(default=())
    intra: bool | None = None

    @property
    def end(self) -> int:
        """The bit offset just after the element."""
        return self.offset + self.width

    def as_dict(self) -> dict:
        """Plain data for JSON (segments carry symbols, labels and intra; other elements do not)."""
        out = {"offset": self.offset, "width": self.width, "kind": self.kind, "name": self.name,
               "value": list(self.value) if isinstance(self.value, tuple) else self.value, "frame": self.frame}
        if self.kind == "segment":
            out.update(symbols=list(self.symbols), labels=list(self.labels), intra=self.intra)
        return out


class _Tracer(_Decoder):
    """The reference decoder, reporting what it reads into ``out``."""

    def __init__(self, reader: BitReader) -> None:
        super().__init__(reader)
        self.out: list[Element] = []
        self.io = syntax.Tracing(reader, self._field)
        self.k: int | None = 0  # the plane the next element belongs to
        self._segment: tuple[int, int, list[int], bool] | None = None

    def _field(self, pos: int, n: int, kind: str, name: str, value: int) -> None:
        self.out.append(Element(pos, n, kind, name, value, self.k))

    def take(self) -> list[Element]:
        out, self.out = self.out, []
        return out

    # ---- what the decoder reads outside the io object ----
    def object_start(self) -> None:
        super().object_start()
        code = self.object_start_code
        self.out.append(Element(0, 32, "start_code", start_code_name(code), code, None))

    def between_planes(self) -> int | None:
        r = self.bits
        start = r.pos
        code = super().between_planes()
        width = r.pos - start
        if width:  # stuffing (maybe none), then 32 bits of start code
            stuffing = width - 32
            value = END_CODE if code is None else code
            frame = None if code is None else self.k
            if stuffing:
                i = start - r.base
                bits = int(bytes(r.buf[i:i + stuffing]).translate(bytes.maketrans(b"\x00\x01", b"01")), 2)
                self.out.append(Element(start, stuffing, "stuffing", "next_start_code() stuffing", bits, frame))
            self.out.append(Element(start + stuffing, 32, "start_code", start_code_name(value), value, frame))
        return code

    def framed_plane(self, k: int, plane_code: int):
        self.k = k
        frame = super().framed_plane(k, plane_code)
        self.k = k + 1
        return frame

    def segment(self, models: list, adapt: bool) -> list[int]:
        start = self.bits.pos
        symbols = super().segment(models, adapt)
        self._segment = (start, self.bits.pos - start, symbols, adapt)
        return symbols

    def decoded(self, part: str, coder: FieldCoder | ValueCoder, values: np.ndarray) -> None:
        start, width, symbols, adapt = self._segment
        labels = tuple(coder.label(int(i)) for i in coder.idx)
        self.out.append(Element(start, width, "segment", SEGMENT_NAMES[part], tuple(int(v) for v in values),
                                self.k, tuple(int(s) for s in symbols), labels, not adapt))

    def trailing(self) -> list[Element]:
        """Bits after the end code, as one element (the decoder stops at the end code)."""
        r = self.bits
        start = r.pos
        while r.more():
            pass
        left = len(r.buf) - r.p
        return [Element(start, left, "trailing", "after the end code (not read)", None, None)] if left else []


def trace(source: Source) -> Iterator[Element]:
    """Every syntax element of ``source`` (bytes, a path or a binary file) in stream order, lazily.

    At a fault the elements read before it are yielded, then the decoder's :class:`FbaError`
    (bit offset, frame) is raised. Reading stops when the caller stops iterating.
    """
    with _opened(source) as src:
        tracer = _Tracer(BitReader(src))
        try:
            for _ in _guarded(tracer):
                yield from tracer.take()
        except FbaError:
            yield from tracer.take()
            raise
        yield from tracer.take()
        yield from tracer.trailing()


def window(elements: Iterable[Element], first: int = 0, stop: int | None = None) -> Iterator[Element]:
    """The elements of frames ``first`` to ``stop - 1``; stops reading at the first element past them.

    Elements of no frame (object start code, end code, trailing bits) are kept when their
    neighbours are: the object start code with frame 0, the end code when the range reaches it.
    """
    for e in elements:
        frame = e.frame
        if frame is None:
            if e.offset == 0 and first > 0:
                continue
            yield e
        elif stop is not None and frame >= stop:
            return
        elif frame >= first:
            yield e


def value_text(e: Element) -> str:
    """An element's value as a person reads it: start codes in hex, stuffing in binary,
    segments as ``label=value`` pairs followed by their symbols."""
    if e.kind == "start_code":
        return f"0x{e.value:08X}"
    if e.kind == "stuffing":
        return f"{e.value:0{e.width}b}"
    if e.kind == "trailing":
        return f"{e.width // 8} bytes" + (f" {e.width % 8} bits" if e.width % 8 else "")
    if e.kind == "segment":
        models = "intra" if e.intra else "P"
        if not e.value:
            return f"{models}, no values (the coder's flush alone)"
        pairs = " ".join(f"{_short(label)}={v}" for label, v in zip(e.labels, e.value))
        return f"{models}, {len(e.value)} values: {pairs}; symbols {' '.join(map(str, e.symbols))}"
    return str(e.value)


def _short(label: str) -> str:
    """'FAP 3' -> '3', 'FAP 1 viseme_select1' -> 'viseme_select1', 'BAP 12' -> '12'."""
    parts = label.split(" ", 2)
    return parts[-1]
