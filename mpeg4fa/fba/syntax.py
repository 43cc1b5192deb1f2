"""Fixed-length header syntax, written once and run both ways.

Each function below describes a piece of the bitstream syntax over an ``io``
object: :class:`Reading` returns the fields it reads (ignoring the values passed
in), :class:`Writing` writes the values passed in and returns them. The decoder
and the encoder call the same functions, so they cannot disagree about the
order or width of a field (the idea of FFmpeg's coded-bitstream templates).
"""
from __future__ import annotations

from functools import lru_cache
from typing import Callable, Sequence

import numpy as np

from .bits import BitReader, BitWriter
from .errors import FbaError, UnsupportedFeature
from .params import PartSpec
from mpeg4fa.spec.frame_rate import FRAME_RATE_BITS, FREQUENCY_OFFSET_BITS, SECONDS_BITS

from .stream import FrameRate, PartParams, RangeSet, TimeCode

MASK_NONE, MASK_HOLD, MASK_INTERPOLATE, MASK_ALL = 0, 1, 2, 3
RANGE_SET_NAMES = ("i_max", "i_min", "p_max", "p_min")


def does_not_fit(what: str, value: int, n: int) -> str:
    return f"{what} = {value} does not fit in {n} bits"


class Reading:
    writing = False

    def __init__(self, reader: BitReader) -> None:
        self.bits = reader

    def u(self, n: int, value: int, what: str) -> int:
        return self.bits.read(n, what)

    def flag(self, value: bool, what: str) -> bool:
        return bool(self.bits.read(1, what))

    def marker(self, what: str) -> None:
        pos = self.bits.pos
        if self.bits.read(1, what) != 1:
            raise FbaError(f"marker bit of {what} is 0", pos)

    def fields(self, widths: Sequence[int], values, what: Callable[[int], str], markers: Sequence[bool]) -> list[int]:
        """Many fixed-width fields at once (``markers[f]``: field f is a marker bit, which must be 1);
        faults are those :meth:`u` and :meth:`marker` would raise, field by field."""
        r = self.bits
        total = sum(widths)
        if not r.available(total):
            for f, n in enumerate(widths):  # the field the stream ends inside
                r.require(n, what(f))
                r.p += n
        start = r.pos
        bits = np.frombuffer(r.digits(total), dtype=np.uint8).astype(np.int64) - ord("0")
        w = np.asarray(widths, dtype=np.int64)
        starts = np.cumsum(w) - w
        place = np.repeat(starts + w - 1, w) - np.arange(total)  # each bit's place value in its field
        values = np.add.reduceat(bits << place, starts) if total else np.zeros(0, dtype=np.int64)
        bad = np.flatnonzero(np.asarray(markers, dtype=bool) & (values != 1))
        if bad.size:
            f = int(bad[0])
            raise FbaError(f"marker bit of {what(f)} is 0", start + int(starts[f]))
        return values.tolist()


Record = Callable[[int, int, str, str, int], None]
"""A tracer's sink: (bit offset, width, kind, name, value) of one element read."""


class Tracing(Reading):
    """:class:`Reading` that also reports every element it reads, with its bit offset and width.

    The syntax trace (:mod:`mpeg4fa.fba.trace`) runs the decoder's own syntax functions
    through this, so the trace cannot disagree with the decoder about a field. An element
    is reported only once it was read whole; a fault inside it is the decoder's error.
    """

    def __init__(self, reader: BitReader, record: Record) -> None:
        super().__init__(reader)
        self.record = record

    def u(self, n: int, value: int, what: str) -> int:
        pos = self.bits.pos
        got = super().u(n, value, what)
        self.record(pos, n, "field", what, got)
        return got

    def flag(self, value: bool, what: str) -> bool:
        pos = self.bits.pos
        got = super().flag(value, what)
        self.record(pos, 1, "field", what, int(got))
        return got

    def marker(self, what: str) -> None:
        pos = self.bits.pos
        super().marker(what)
        self.record(pos, 1, "marker", f"marker bit of {what}", 1)

    def fields(self, widths: Sequence[int], values, what: Callable[[int], str], markers: Sequence[bool]) -> list[int]:
        """Field by field: a fault names the first bad field after the good ones were reported."""
        pos = self.bits.pos
        try:
            got = super().fields(widths, values, what, markers)
        except FbaError as exc:
            got, fault = None, exc
        else:
            fault = None
        for f, n in enumerate(widths):
            if fault is not None and fault.bit_offset is not None and pos + n > fault.bit_offset:
                break
            value = got[f] if got is not None else None
            if value is None:  # the batch failed: read this good field again for its value
                value = int(self._bits_at(pos, n), 2) if n else 0
            name = what(f)
            self.record(pos, n, "marker" if markers[f] else "field",
                        f"marker bit of {name}" if markers[f] else name, int(value))
            pos += n
        if fault is not None:
            raise fault
        return got

    def _bits_at(self, pos: int, n: int) -> str:
        """``n`` bits at absolute offset ``pos`` (within the reader's window) as '0'/'1' text."""
        r = self.bits
        i = pos - r.base
        return bytes(r.buf[i:i + n]).translate(bytes.maketrans(b"\x00\x01", b"01")).decode()


class Writing:
    writing = True

    def __init__(self, writer: BitWriter) -> None:
        self.bits = writer

    def u(self, n: int, value: int, what: str) -> int:
        if not 0 <= int(value) < (1 << n):
            raise FbaError(does_not_fit(what, value, n), self.bits.pos)
        self.bits.write(n, int(value))
        return int(value)

    def flag(self, value: bool, what: str) -> bool:
        self.bits.write(1, int(bool(value)))
        return bool(value)

    def marker(self, what: str) -> None:
        self.bits.write(1, 1)

    def fields(self, widths: Sequence[int], values, what: Callable[[int], str], markers: Sequence[bool]) -> list[int]:
        """Many fixed-width fields at once (markers are written as 1)."""
        out = []
        for f, (n, value, is_marker) in enumerate(zip(widths, values, markers)):
            if is_marker:
                self.marker(what(f))
                out.append(1)
            else:
                out.append(self.u(n, value, what(f)))
        return out


def frame_rate(io, fr: FrameRate | None) -> FrameRate | None:
    if not io.flag(fr is not None, "is_frame_rate"):
        return None
    fr = fr or FrameRate(0)
    return FrameRate(io.u(FRAME_RATE_BITS, fr.frame_rate, "frame_rate"), io.u(SECONDS_BITS, fr.seconds, "seconds"),
                     io.u(FREQUENCY_OFFSET_BITS, fr.frequency_offset, "frequency_offset"))


def time_code(io, tc: TimeCode | None) -> TimeCode | None:
    if not io.flag(tc is not None, "is_time_code"):
        return None
    tc = tc or TimeCode(0, 0, 0)
    hours = io.u(5, tc.hours, "time_code_hours")
    minutes = io.u(6, tc.minutes, "time_code_minutes")
    io.marker("time_code")
    return TimeCode(hours, minutes, io.u(6, tc.seconds, "time_code_seconds"))


def skip_frames(io, skip: int, pad: bool = False) -> int:
    """number_of_frames_to_skip in 4-bit chunks, continued while a chunk is 15.

    ``pad`` sends the flag with a count of 0 (5 bits that change nothing), which
    the encoder uses to keep a tiny frame from hiding inside start-code stuffing.
    """
    if not io.flag(skip > 0 or pad, "skip_frames"):
        return 0
    total, remaining = 0, skip
    while True:
        chunk = io.u(4, min(remaining, 15), "number_of_frames_to_skip")
        total += chunk
        remaining -= chunk
        if chunk != 15:
            return total


def temporal_header(io, is_intra: bool, fr: FrameRate | None, tc: TimeCode | None, skip: int,
                    pad: bool = False) -> tuple[FrameRate | None, TimeCode | None, int]:
    """The temporal part of the plane header (sent once, by the face or else the body part)."""
    if is_intra:
        fr = frame_rate(io, fr)
        tc = time_code(io, tc)
    return fr, tc, skip_frames(io, skip, pad)


def group_masks(io, groups: Sequence[Sequence[int]], mask_types: Sequence[int], mask: np.ndarray,
                n: int, label: str = "parameter") -> tuple[tuple[int, ...], np.ndarray]:
    """A marker, a 2-bit mask type and (types 1 and 2) a per-parameter mask, per group."""
    types, out = [], np.zeros(n, dtype=bool)
    for g, members in enumerate(groups):
        io.marker(f"group {g + 1} mask")
        t = io.u(2, mask_types[g] if io.writing else 0, f"mask type of {label} group {g + 1}")
        types.append(t)
        if t in (MASK_HOLD, MASK_INTERPOLATE):
            sent = [int(mask[i]) for i in members] if io.writing else None
            out[list(members)] = io.fields([1] * len(members), sent, lambda f: f"mask bit of {label} {members[f] + 1}",
                                           markers=[False] * len(members))
        elif t == MASK_ALL:
            out[list(members)] = True
    return tuple(types), out


@lru_cache(maxsize=256)
def _minmax_layout(groups: tuple[tuple[int, ...], ...], mask: bytes) -> tuple[int | None, ...]:
    """The fields of one new-range set in order: None for a marker bit, i for parameter i's 5-bit code
    (``mask`` as bytes, one per parameter: a stream's headers repeat a few masks, so this is cached)."""
    layout: list[int | None] = []
    for members in groups:
        for j, i in enumerate(members):
            if j % 4 == 0:
                layout.append(None)
            if mask[i]:
                layout.append(i)
    return tuple(layout)


def new_minmax(io, groups: Sequence[Sequence[int]], mask: np.ndarray, ranges: RangeSet,
               label: str = "parameter") -> RangeSet:
    """The four new-range sets: a marker every 4 parameters of a group, 5 bits per masked one.

    The sets an intra header flags follow one another, so they are read (or written) as one run of fields.
    """
    flags = tuple(io.flag(ranges.flags[k], f"is_{name}_new") for k, name in enumerate(RANGE_SET_NAMES))
    codes = np.zeros_like(ranges.codes)
    sets = [k for k in range(4) if flags[k]]
    if not sets:
        return RangeSet(flags, codes)
    layout = _minmax_layout(tuple(map(tuple, groups)), np.asarray(mask, dtype=np.uint8).tobytes())
    size = len(layout)
    markers = [i is None for i in layout]
    widths = [1 if m else 5 for m in markers]
    sent = [1 if i is None else int(ranges.codes[k, i]) for k in sets for i in layout] if io.writing else None

    def what(f: int) -> str:
        name, i = RANGE_SET_NAMES[sets[f // size]], layout[f % size]
        return f"new {name} ranges" if i is None else f"new {name} of {label} {i + 1}"

    got = np.asarray(io.fields(widths * len(sets), sent, what, markers=markers * len(sets)), dtype=np.int64)
    coded = np.array([i for i in layout if i is not None], dtype=np.int64)
    is_code = ~np.array(markers, dtype=bool)
    for row, k in enumerate(sets):
        codes[k, coded] = got.reshape(len(sets), size)[row, is_code]
    return RangeSet(flags, codes)


def part_intra_header(io, params: PartParams | None, part: PartSpec) -> PartParams:
    """quant, group masks, gender, coding type and (predictive mode) new ranges of one part."""
    label, n = part.label, part.n
    w = params if io.writing else None
    quant = io.u(5, w.quant if w else 0, f"{label.lower()}_quant")
    types, mask = group_masks(io, part.mask_groups, w.mask_types if w else (), w.mask if w else None, n, label)
    gender = io.u(1, w.gender if w else 0, "suggested_gender")
    pos = io.bits.pos
    coding_type = io.u(1, w.coding_type if w else 0, "coding_type")
    if coding_type == 1:
        raise UnsupportedFeature("DCT segment mode (coding_type 1) is not supported: its syntax is not "
                                 "published in any source available to this project", pos)
    ranges = new_minmax(io, part.range_groups, mask, w.ranges if w else RangeSet.none(n), label)
    return PartParams(quant, types, mask, gender, coding_type, ranges)
