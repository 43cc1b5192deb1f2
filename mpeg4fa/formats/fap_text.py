"""Plain-text ``.fap`` files: the exchange format of Xface, Greta, VREng and visage.

Layout (facts file §6.1)::

    # comment lines, anywhere
    <version> <name> <fps> <number_of_frames>
    <mask line: 68 entries 0/1, FAP 1..68>        } repeated
    <frame line: frame number, masked values>     } per frame

FAP 1 (viseme) takes 4 integers on a frame line (select1 select2 blend def),
FAP 2 (expression) takes 6 (select1 intensity1 select2 intensity2 init_face
expression_def), every other masked FAP one integer in FAPU units (§4.3).

Files come from several programs with their own quirks (CRLF and trailing spaces
from Xface, 69-entry masks from Greta, a leading comment from VREng, names with
spaces), so the reader is lenient about layout and strict about numbers: every
problem is a :class:`FormatError` pointing at the line and column to fix.

Limits, so that a few bytes cannot ask for absurd work: a line holds at most
:data:`MAX_LINE_CHARS` characters; the frame rate must be one an FBA intra header
can carry (1/16 to 255 15/16 fps, :func:`mpeg4fa.fba.limits.fps_problem`); frame
numbers stay within 24 h of frames at that rate (:func:`mpeg4fa.fba.limits.frame_limit`;
a gap between frame numbers is a ``skip`` count, never materialised frames); FAP
values fit int32 and FAP 1/FAP 2 fields their ranges
(:func:`mpeg4fa.spec.profiles.high_level_problem`). The header's frame count is
not trusted and allocates nothing. Files are read as UTF-8 (a BOM is skipped);
UTF-16 text or NUL bytes are refused as "not a text .fap file". The grammar (lines, numbers,
header, mask/frame pairs, the writer's layout) is the one ``.bap`` files share,
:mod:`mpeg4fa.formats.masked_text`; what is the face's own (68-entry masks, the FAP 1/FAP 2 fields,
the versions) is here.
"""
from __future__ import annotations

import warnings
from typing import Iterator, NamedTuple, cast

import numpy as np

from mpeg4fa.decoded import explicit
from mpeg4fa.fba.stacking import StreamBuilder
from mpeg4fa.fba.stream import N_FAPS, FapStream
from mpeg4fa.formats.errors import FormatError, FormatWarning
from mpeg4fa.formats.masked_text import (
    INT32_MAX, INT32_MIN, MAX_LINE_CHARS, Dialect, Header, Line, Source, Target, build_stream, check_version,
    frame_number, frame_numbers, frame_text, frame_values, header_name, header_text, mask_entries, mask_text, parse,
    stream_fps, target_label, write_lines,
)
from mpeg4fa.spec.profiles import first_high_level_fault, high_level_problem

__all__ = ["EXPRESSION_WIDTH", "INT32_MAX", "INT32_MIN", "MAX_LINE_CHARS", "SUPPORTED_VERSIONS", "VISEME_WIDTH",
           "FapHeader", "FapRecord", "Source", "Target", "iter_fap", "read_fap", "write_fap"]

SUPPORTED_VERSIONS = ("1.1", "2.0", "2.1", "2.2")
"""Header versions read (all with the same layout) and accepted by :func:`write_fap`."""

VISEME_WIDTH = 4
EXPRESSION_WIDTH = 6


class FapHeader(Header):
    """A ``.fap`` header line (:class:`~mpeg4fa.formats.masked_text.Header`); readers do not rely on ``n_frames``."""

    __slots__ = ()


class FapRecord(NamedTuple):
    """One frame as :func:`iter_fap` yields it; arrays use the :class:`FapStream` layouts."""

    frame_number: int
    mask: np.ndarray        # (68,) bool, FAP 1 in column 0
    values: np.ndarray      # (68,) int32, columns 0 and 1 zero
    viseme: np.ndarray      # (4,) int32
    expression: np.ndarray  # (6,) int32


# ---- reading ------------------------------------------------------------------------


def _parse_mask(line: Line, path: str) -> np.ndarray:
    entries = mask_entries(line, path, "FAP 1..68")
    if len(entries) < N_FAPS:
        raise FormatError(path, line.number, line.column(len(entries)),
                          f"the mask line has {len(entries)} entries, expected {N_FAPS}",
                          "give one 0/1 entry for each of FAPs 1..68")
    # Greta writes 69 entries: anything after the 68th is ignored
    return np.array(entries[:N_FAPS], dtype=bool)


def _value_count(mask: np.ndarray) -> int:
    """Integers a frame line carries after its frame number, for this mask."""
    return VISEME_WIDTH * int(mask[0]) + EXPRESSION_WIDTH * int(mask[1]) + int(mask[2:].sum())


def _parse_frame(line: Line, mask: np.ndarray, mask_line: Line, previous: int, path: str, fps: float,
                 limit: int) -> FapRecord:
    number = frame_number(line, path, previous, fps, limit)
    ints = frame_values(line, path, number, _value_count(mask), mask_line,
                        "give one value per masked FAP, 4 for FAP 1 and 6 for FAP 2, in FAP order",
                        "FAP values are whole numbers in FAPU")
    first = 1  # token index of the FAP 1 fields, then of the FAP 2 fields
    for fap, width in ((1, VISEME_WIDTH), (2, EXPRESSION_WIDTH)):
        if mask[fap - 1]:
            fault = high_level_problem(fap, ints[first - 1:first - 1 + width])
            if fault is not None:
                k, problem, hint = fault
                raise FormatError(path, line.number, line.column(first + k), f"frame {number}: {problem}", hint)
            first += width
    return _record(number, mask, np.array(ints, dtype=np.int32))


def _record(number: int, mask: np.ndarray, flat: np.ndarray) -> FapRecord:
    """Split a frame line's values into the FAP 1, FAP 2 and FAP 3..68 arrays."""
    viseme = np.zeros(VISEME_WIDTH, dtype=np.int32)
    expression = np.zeros(EXPRESSION_WIDTH, dtype=np.int32)
    values = np.zeros(N_FAPS, dtype=np.int32)
    pos = 0
    if mask[0]:
        viseme[:] = flat[pos:pos + VISEME_WIDTH]
        pos += VISEME_WIDTH
    if mask[1]:
        expression[:] = flat[pos:pos + EXPRESSION_WIDTH]
        pos += EXPRESSION_WIDTH
    values[2:][mask[2:]] = flat[pos:]
    return FapRecord(number, mask, values, viseme, expression)


# Version 2.0: VREng divides its values by 20 (FAPV20_DIV); what that means was never checked,
# so 2.0 files are read exactly like 2.1 (values as written, in FAPU).
_FAP = Dialect(suffix=".fap", versions=SUPPORTED_VERSIONS, default_version="2.1", example_name="joy.fap",
               header=FapHeader, mask=_parse_mask, frame=_parse_frame)


def iter_fap(source: Source, *, name: str | None = None) -> Iterator[FapRecord]:
    """Yield ``(frame_number, mask, values, viseme, expression)`` per frame, reading lazily.

    Nothing is opened until the first frame is asked for, and only one line is held
    at a time, so long files stream. The header is still checked. ``name`` replaces
    the path in error messages (useful for streams).
    """
    records = parse(source, name, _FAP)
    next(records)  # the header
    yield from records  # type: ignore[misc]


def _add_face(builder: StreamBuilder, record: FapRecord, timestamp: float) -> None:
    builder.add(fap_mask=record.mask, fap_values=record.values, viseme=record.viseme,
                expression=record.expression, timestamp=timestamp)


def read_fap(source: Source, *, name: str | None = None) -> FapStream:
    """Read a ``.fap`` file (path or text stream) into a :class:`FapStream`.

    Gaps in the frame numbers become ``skip`` on the frame before the gap;
    timestamps are ``frame_number / fps``. The header's frame count is not
    trusted: the frames found are what is returned.
    """
    records = parse(source, name, _FAP)
    header = cast(FapHeader, next(records))
    return build_stream(cast("Iterator[FapRecord]", records), header.fps, _add_face)


# ---- writing ------------------------------------------------------------------------


def write_fap(stream: FapStream, target: Target, *, name: str | None = None, version: str = "2.1") -> None:
    """Write ``stream`` as a ``.fap`` file in the common 2.1 layout.

    Frame numbers start at 0 and grow by ``skip + 1``, so skipped frames show as
    gaps; FAPs the stream leaves to interpolation (mask type 2) are written as sent
    (:func:`mpeg4fa.decoded.explicit`: the format has no mask types); timestamps are
    not written (readers rebuild them from fps). BAPs have no place in the format:
    they are dropped with a warning. Everything is
    checked before the first byte is written, so a bad stream leaves no partial file.
    """
    label = target_label(target)
    stream = explicit(stream)  # a .fap cannot say "interpolate": FAPs a decoder copies are written out
    fps = stream_fps(stream, label)
    numbers = frame_numbers(stream, label, fps)
    _check_high_level(stream, label)
    n_frames = int(numbers[-1]) + 1 if len(numbers) else 0
    check_version(label, ".fap", SUPPORTED_VERSIONS, version)
    header = header_text(label, header_name(name, label, ".fap"), _FAP.example_name, version, fps, n_frames)
    if stream.bap_mask.any():
        warnings.warn(f"{int(stream.bap_mask.any(axis=1).sum())} frames carry BAPs (body animation); "
                      ".fap holds face parameters only, so the BAPs are dropped", FormatWarning, stacklevel=2)
    write_lines(target, _format_lines(stream, header, numbers))


def _check_high_level(stream: FapStream, label: str) -> None:
    """FAP 1/FAP 2 fields the reader would refuse are refused before anything is written."""
    for fap, table in ((1, stream.viseme), (2, stream.expression)):
        sent = np.asarray(stream.fap_mask, dtype=bool)[:, fap - 1]
        fault = first_high_level_fault(fap, np.where(sent[:, None], table, 0))
        if fault is not None:
            k, _, problem, hint = fault
            raise FormatError(label, 2 * k + 3, None, f"frame {k}: {problem}", hint)


def _format_lines(stream: FapStream, header: str, numbers: np.ndarray) -> Iterator[str]:
    yield header + "\n"
    masks = np.asarray(stream.fap_mask, dtype=bool)
    for k in range(len(numbers)):
        mask = masks[k]
        yield mask_text(mask)
        values: list[int] = []
        if mask[0]:
            values += stream.viseme[k].tolist()
        if mask[1]:
            values += stream.expression[k].tolist()
        values += stream.fap_values[k, 2:][mask[2:]].tolist()
        yield frame_text(int(numbers[k]), values)
