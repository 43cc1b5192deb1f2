"""Plain-text ``.bap`` files: body animation (BAPs), the counterpart of ``.fap``, in VREng's dialect.

Layout, as VREng reads and ships it (philippedax/vreng ``src/model/bap.cpp``, ``bap.hpp``,
``src/world/humanoid.cpp`` and the files under ``data/bap/``, e.g. ``hi.bap``, ``100.bap``)::

    # comment lines, anywhere
    <version> <name> <fps> <number_of_frames>      e.g. '3.2 hello.bap 15 49', '3.1 100.bap 5 37'
    <mask line: one 0/1 per BAP>                   } repeated
    <frame line: frame number, masked values>      } per frame

Facts checked in those sources:

* version ``3.1`` or ``3.2`` (``HEAD_BAP_V31``, ``HEAD_BAP_V32``); ``2.0``/``2.1`` headers go to
  the same VREng reader but are ``.fap`` files (:mod:`mpeg4fa.formats.fap_text`);
* VREng's mask lines have 186 entries, BAPs 1..186 (``NUM_BAPS_V31`` = ``NUM_BAPS_V32`` = 186),
  the ISO BAPs (:data:`mpeg4fa.spec.N_ISO_BAPS`, ``spec/bap_sets.csv``); ``100.bap`` ends its mask
  lines with a space;
* a frame line is the frame number, then one integer per masked BAP in BAP order; the header's
  frame count is the last header field (VREng takes it after the last space);
* the numbers are written as integers; VREng turns an angle into degrees by dividing by 1745
  (``BAPV31_DIV``, pi x 1e5 / 180: the angle is in 1e-5 rad) in 3.1 files and by 555 (``BAPV32_DIV``,
  1e5 / 180) in 3.2 files, and the translations BAP 181..183 (``TR_VERTICAL``..``TR_FRONTAL``) not
  at all. 100.bap (3.1) turns BAP 100 a full circle, 0, -17453, ... -296705, 314159, 296706, ... 0:
  steps of 10 degrees at 1e-5 rad;
* ``Bap::parse`` skips empty lines and lines starting with ``#``.

What this module chooses:

* mask lines are read with 186 entries (BAPs 187..296 unsent) or 296 (:data:`mpeg4fa.spec.N_BAPS`,
  the extension BAPs too, which real body-only streams send); any other count is an error;
* values are read and written as they stand, in the stream's BAP units, whatever the version says:
  nothing is rescaled (a 3.2 file shows larger angles in VREng than the same numbers in a 3.1 file);
  the writer writes 3.1 by default, whose reading of angles (1e-5 rad) is the one the FAP angle unit
  uses (:data:`mpeg4fa.spec.ANGLE_UNIT`);
* the writer writes 186-entry masks (VREng reads them) unless an extension BAP is sent, then 296.

The reader is lenient about layout and strict about numbers, as :mod:`mpeg4fa.formats.fap_text`
is (the same grammar, :mod:`mpeg4fa.formats.masked_text`: CRLF, trailing spaces, ``#`` comments,
a BOM, the same limits on line length, frame rate, frame numbers and int32 values): every problem
is one :class:`FormatError` at ``path:line:column``. A ``.bap`` stream has body frames only (object
mask 2); a face and a body file are joined by :func:`merge_face_body` and a stream split by
:func:`split_face_body`.
"""
from __future__ import annotations

import warnings
from dataclasses import replace
from typing import Iterator, NamedTuple, cast

import numpy as np

from mpeg4fa.fba.stacking import StreamBuilder, no_body
from mpeg4fa.fba.stream import BODY, FACE, N_BAPS, FapStream
from mpeg4fa.formats.errors import FormatError, FormatWarning
from mpeg4fa.formats.fap_text import SUPPORTED_VERSIONS as FAP_VERSIONS
from mpeg4fa.formats.masked_text import (
    Dialect, Header, Line, Source, Target, build_stream, check_version, frame_number, frame_numbers, frame_text,
    frame_values, header_name, header_text, mask_entries, mask_text, parse, stream_fps, target_label, write_lines,
)
from mpeg4fa.spec import N_ISO_BAPS

SUPPORTED_VERSIONS = ("3.1", "3.2")
"""Header versions read (one layout) and accepted by :func:`write_bap`: VREng's BAP versions."""

MASK_WIDTHS = (N_ISO_BAPS, N_BAPS)
"""Entries a mask line may have: the ISO BAPs (VREng's files), or all of them with the extension BAPs."""


class BapHeader(Header):
    """A ``.bap`` header line (:class:`~mpeg4fa.formats.masked_text.Header`); readers do not rely on ``n_frames``."""

    __slots__ = ()


class BapRecord(NamedTuple):
    """One frame as :func:`iter_bap` yields it, in the :class:`FapStream` layouts."""

    frame_number: int
    mask: np.ndarray    # (296,) bool, BAP 1 in column 0
    values: np.ndarray  # (296,) int32, zero where not masked


# ---- reading ------------------------------------------------------------------------


def _parse_mask(line: Line, path: str) -> np.ndarray:
    entries = mask_entries(line, path, "BAP")
    if len(entries) not in MASK_WIDTHS:
        # past the end of a short line, else at the first entry beyond the nearest width below
        column = line.column(max([w for w in MASK_WIDTHS if w < len(entries)], default=len(entries)))
        raise FormatError(path, line.number, column,
                          f"the mask line has {len(entries)} entries, expected {N_ISO_BAPS} or {N_BAPS}",
                          f"give one 0/1 for each of BAPs 1..{N_ISO_BAPS} (as VREng writes) or 1..{N_BAPS} "
                          "(with the extension BAPs)")
    mask = np.zeros(N_BAPS, dtype=bool)
    mask[:len(entries)] = entries
    return mask


def _parse_frame(line: Line, mask: np.ndarray, mask_line: Line, previous: int, path: str, fps: float,
                 limit: int) -> BapRecord:
    number = frame_number(line, path, previous, fps, limit, past="past the span a stream may have")
    values = np.zeros(N_BAPS, dtype=np.int32)
    values[mask] = frame_values(line, path, number, int(mask.sum()), mask_line,
                                "give one whole number per masked BAP, in BAP order",
                                "BAP values are whole numbers in BAP units (angles 1e-5 rad)")
    return BapRecord(number, mask, values)


_BAP = Dialect(suffix=".bap", versions=SUPPORTED_VERSIONS, default_version="3.1", example_name="wave.bap",
               header=BapHeader, mask=_parse_mask, frame=_parse_frame, other_versions=FAP_VERSIONS,
               other_hint="version {version} is a .fap (face) file: read it with read_fap")


def read_bap_header(source: Source, *, name: str | None = None) -> BapHeader:
    """The header line alone (version, name, fps, claimed frame count), checked; the frames are not read."""
    records = parse(source, name, _BAP)
    try:
        return cast(BapHeader, next(records))
    finally:
        records.close()  # closes the file now, not when the generator is collected


def iter_bap(source: Source, *, name: str | None = None) -> Iterator[BapRecord]:
    """Yield ``(frame_number, mask, values)`` per frame, reading lazily, one line at a time.

    The header is checked first; ``name`` replaces the path in error messages.
    """
    records = parse(source, name, _BAP)
    next(records)  # the header
    yield from records  # type: ignore[misc]


_NO_FACE = FapStream.empty(1)  # the face rows of a body-only frame: nothing sent


def _add_body(builder: StreamBuilder, record: BapRecord, timestamp: float) -> None:
    builder.add(fap_mask=_NO_FACE.fap_mask[0], fap_values=_NO_FACE.fap_values[0], viseme=_NO_FACE.viseme[0],
                expression=_NO_FACE.expression[0], timestamp=timestamp, object_mask=BODY,
                bap_mask=record.mask, bap_values=record.values)


def read_bap(source: Source, *, name: str | None = None) -> FapStream:
    """Read a ``.bap`` file (path or text stream) into a body-only :class:`FapStream` (object mask 2).

    Gaps in the frame numbers become ``skip`` on the frame before the gap; timestamps are
    ``frame_number / fps``. The header's frame count is not trusted.
    """
    records = parse(source, name, _BAP)
    header = cast(BapHeader, next(records))
    return build_stream(cast("Iterator[BapRecord]", records), header.fps, _add_body)


# ---- writing ------------------------------------------------------------------------


def write_bap(stream: FapStream, target: Target, *, name: str | None = None, version: str = "3.1",
              width: int | None = None) -> None:
    """Write the body frames of ``stream`` (object mask bit 2) as a ``.bap`` file.

    Frame numbers are those of the whole stream (0, then ``skip + 1`` on), so that the ``.fap``
    and ``.bap`` of one stream agree frame for frame; frames without body data are gaps. ``width``
    is the mask line's length (186 or 296); by default 186 unless a BAP above 186 is sent. FAPs have
    no place in the format: they are dropped with a :class:`FormatWarning`. Everything is checked
    before the first byte is written, so a bad stream leaves no partial file.
    """
    label = target_label(target)
    check_version(label, ".bap", SUPPORTED_VERSIONS, version)
    fps = stream_fps(stream, label)
    numbers = frame_numbers(stream, label, fps)
    body = np.flatnonzero(np.asarray(stream.object_mask) & BODY)
    masks = np.asarray(stream.bap_mask[body], dtype=bool)
    width = _mask_width(masks, width, label)
    n_frames = int(numbers[-1]) + 1 if len(numbers) else 0
    header = header_text(label, header_name(name, label, ".bap").strip(), _BAP.example_name, version, fps, n_frames)
    if np.asarray(stream.fap_mask, dtype=bool).any():
        warnings.warn(f"{int(np.asarray(stream.fap_mask).any(axis=1).sum())} frames carry FAPs (face animation); "
                      ".bap holds body parameters only, so the FAPs are dropped", FormatWarning, stacklevel=2)
    write_lines(target, _format_lines(header, numbers[body], masks, stream.bap_values[body], width))


def _mask_width(masks: np.ndarray, width: int | None, label: str) -> int:
    extension = bool(masks[:, N_ISO_BAPS:].any())
    if width is None:
        return N_BAPS if extension else N_ISO_BAPS
    if width not in MASK_WIDTHS:
        raise FormatError(label, 2, None, f"cannot write mask lines of {width} entries",
                          f"a mask line has {N_ISO_BAPS} or {N_BAPS} entries")
    if width < N_BAPS and extension:
        k = int(np.argmax(masks[:, N_ISO_BAPS:].any(axis=1)))
        bap = N_ISO_BAPS + 1 + int(np.argmax(masks[k, N_ISO_BAPS:]))
        raise FormatError(label, 2 * k + 2, None,
                          f"body frame {k} sends BAP {bap}, which a {width}-entry mask line cannot hold",
                          f"write {N_BAPS}-entry mask lines (width={N_BAPS}, the default for such streams)")
    return width


def _format_lines(header: str, numbers: np.ndarray, masks: np.ndarray, values: np.ndarray,
                  width: int) -> Iterator[str]:
    yield header + "\n"
    for number, mask, row in zip(numbers.tolist(), masks, values):
        yield mask_text(mask[:width])
        yield frame_text(number, row[mask].tolist())


# ---- face + body --------------------------------------------------------------------


def has_face(stream: FapStream) -> bool:
    """Whether any frame carries the face part (object mask bit 1)."""
    return bool((np.asarray(stream.object_mask) & FACE).any())


def has_body(stream: FapStream) -> bool:
    """Whether any frame carries the body part with at least one BAP sent."""
    return bool(np.asarray(stream.bap_mask, dtype=bool).any())


def split_face_body(stream: FapStream) -> tuple[FapStream, FapStream]:
    """The stream as its face part (BAPs removed) and its body part (FAPs removed), for a ``.fap`` and
    a ``.bap`` file; both keep every frame, so :func:`write_fap` and :func:`write_bap` number them alike."""
    n = len(stream)
    face = replace(stream, object_mask=np.asarray(stream.object_mask) & FACE)
    face.bap_mask, face.bap_values = no_body(n)
    empty = FapStream.empty(n)
    body = replace(stream, object_mask=np.asarray(stream.object_mask) & BODY, fap_mask=empty.fap_mask,
                   fap_values=empty.fap_values, viseme=empty.viseme, expression=empty.expression)
    return face, body


def _frame_grid(stream: FapStream, fps: float) -> np.ndarray:
    """Frame numbers of a stream read from text (timestamps are ``number / fps``)."""
    return np.rint(np.asarray(stream.timestamps, dtype=np.float64) * fps).astype(np.int64)


def merge_face_body(face: FapStream, body: FapStream, *, body_label: str = "<body>") -> FapStream:
    """One face+body stream from a ``.fap`` stream and a ``.bap`` stream, frames matched by frame number.

    A frame of the face stream carries the face part (object mask bit 1), a frame of the body stream the
    body part (bit 2); a frame in both carries both. The two must have one frame rate: a mismatch is a
    :class:`FormatError` on the body file's header (``body_label``).
    """
    fps = float(face.fps)
    if abs(float(body.fps) - fps) > 1e-9 * max(fps, 1.0):
        raise FormatError(body_label, 1, None, f"frame rate {float(body.fps):g} differs from the face file's {fps:g}",
                          "give the .fap and .bap files of one stream, or fix the fps field of a header")
    face_numbers, body_numbers = _frame_grid(face, fps), _frame_grid(body, fps)
    numbers = np.union1d(face_numbers, body_numbers)
    out = FapStream.empty(len(numbers), object_mask=0)
    f = np.searchsorted(numbers, face_numbers)
    b = np.searchsorted(numbers, body_numbers)
    for field in ("fap_mask", "fap_values", "viseme", "expression"):
        getattr(out, field)[f] = getattr(face, field)
    out.bap_mask[b] = np.asarray(body.bap_mask, dtype=bool)
    out.bap_values[b] = body.bap_values
    out.object_mask[f] |= FACE
    out.object_mask[b] |= BODY
    out.timestamps = numbers / fps
    if len(numbers):
        out.skip[:-1] = np.diff(numbers) - 1
    out.source_fps = fps
    out.mask_types = face.mask_types
    return out
