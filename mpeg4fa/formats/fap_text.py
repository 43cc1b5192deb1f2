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
UTF-16 text or NUL bytes are refused as "not a text .fap file".
"""
from __future__ import annotations

import io
import os
import re
import warnings
from array import array
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Iterable, Iterator, NamedTuple, Union, cast

import numpy as np

from mpeg4fa.decoded import explicit
from mpeg4fa.fba.limits import MAX_SPAN_SECONDS, fps_problem, frame_limit
from mpeg4fa.fba.stacking import StreamBuilder
from mpeg4fa.fba.stream import N_FAPS, FapStream
from mpeg4fa.formats.errors import FormatError, FormatWarning
from mpeg4fa.spec.profiles import first_high_level_fault, high_level_problem

SUPPORTED_VERSIONS = ("1.1", "2.0", "2.1", "2.2")
"""Header versions read (all with the same layout) and accepted by :func:`write_fap`."""

VISEME_WIDTH = 4
EXPRESSION_WIDTH = 6
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1

Source = Union[str, "os.PathLike[str]", IO[str]]
Target = Union[str, "os.PathLike[str]", IO[str]]

_TOKEN = re.compile(r"\S+")
_INT = re.compile(r"[+-]?[0-9]+\Z")
_FLOAT = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z")
_MAX_INT_DIGITS = 12  # longer than any int32, short enough for int() to stay cheap and safe
_MAX_TOKEN = 24
"""Longest number token read; an int32 with sign takes 11 characters, a few leading zeros are tolerated."""
MAX_LINE_CHARS = 1 << 16
"""Longest line read (65,536 characters): a frame line of all 68 FAPs takes about 1,000."""
_UTF16_BOMS = (b"\xff\xfe", b"\xfe\xff")


class FapHeader(NamedTuple):
    """The header line. ``n_frames`` is what the writer claimed; readers do not rely on it."""

    version: str
    name: str
    fps: float
    n_frames: int


class FapRecord(NamedTuple):
    """One frame as :func:`iter_fap` yields it; arrays use the :class:`FapStream` layouts."""

    frame_number: int
    mask: np.ndarray        # (68,) bool, FAP 1 in column 0
    values: np.ndarray      # (68,) int32, columns 0 and 1 zero
    viseme: np.ndarray      # (4,) int32
    expression: np.ndarray  # (6,) int32


# ---- reading: lines -----------------------------------------------------------------


class _Line:
    """A content line with its 1-based number; columns are computed only for errors."""

    __slots__ = ("number", "text", "tokens")

    def __init__(self, number: int, text: str) -> None:
        self.number = number
        self.text = text
        self.tokens: list[str] = _TOKEN.findall(text)

    def column(self, index: int) -> int:
        """Column of token ``index``, or just past the last token when there is none."""
        spans = [m.span() for m in _TOKEN.finditer(self.text)]
        if index < len(spans):
            return spans[index][0] + 1
        return (spans[-1][1] if spans else 0) + 1

    def span_text(self, first: int, last: int) -> str:
        """The raw text from token ``first`` to token ``last`` inclusive (keeps inner spaces)."""
        spans = [m.span() for m in _TOKEN.finditer(self.text)]
        return self.text[spans[first][0]:spans[last][1]]


def _bounded_lines(handle: Iterable[str | bytes]) -> Iterator[str | bytes]:
    """The handle's lines, none longer than :data:`MAX_LINE_CHARS` + 1 (so a file without line ends
    cannot fill memory): ``readline`` with a limit where the handle has one."""
    readline = getattr(handle, "readline", None)
    if readline is None:
        yield from handle
        return
    while line := readline(MAX_LINE_CHARS + 1):
        yield line


class _LineReader:
    """Skips blank and ``#`` lines, and counts lines so that end-of-file errors can say where."""

    def __init__(self, handle: Iterable[str | bytes], path: str) -> None:
        self._lines = _bounded_lines(handle)
        self.path = path
        self.count = 0

    def next(self) -> _Line | None:
        while True:
            try:
                raw = next(self._lines)
            except StopIteration:
                return None
            except UnicodeDecodeError as exc:
                raise FormatError(self.path, self.count + 1, None, f"the line is not valid text ({exc.reason})",
                                  "save the file as ASCII or UTF-8") from None
            except OSError as exc:
                raise FormatError.from_os_error(self.path, exc) from None
            self.count += 1
            text = raw.decode("utf-8", "replace") if isinstance(raw, bytes) else raw
            if self.count == 1:
                text = text.lstrip("\ufeff")  # a byte-order mark is not part of the header
            self._check_text(text)
            stripped = text.strip()
            if stripped and not stripped.startswith("#"):
                return _Line(self.count, text.rstrip("\r\n"))

    def _check_text(self, text: str) -> None:
        if len(text) > MAX_LINE_CHARS:
            raise FormatError(self.path, self.count, None, f"line is longer than {MAX_LINE_CHARS:,} characters",
                              "a .fap line holds the header, a mask or one frame; is this a .fap file?")
        nul = text.find("\x00")
        if nul >= 0:
            raise FormatError(self.path, self.count, nul + 1, "NUL byte: this is not a text .fap file",
                              "an .fba stream is read by decode() or read_stream(); UTF-16 text must be saved "
                              "as UTF-8")

    def error_at_end(self, problem: str, hint: str) -> FormatError:
        return FormatError(self.path, self.count + 1, None, problem, hint)


@contextmanager
def _open_source(source: Source, name: str | None) -> Iterator[tuple[Iterable[str], str]]:
    """Yield (lines, label for messages); close the file only if we opened it."""
    if isinstance(source, (str, bytes, os.PathLike)):
        label = name if name is not None else os.fsdecode(source)
        try:
            raw = open(source, "rb")
        except OSError as exc:
            raise FormatError.from_os_error(label, exc) from None
        with raw:
            try:
                head = raw.peek(2)[:2] if hasattr(raw, "peek") else b""
            except OSError as exc:
                raise FormatError.from_os_error(label, exc) from None
            if head in _UTF16_BOMS:
                raise FormatError(label, 1, 1, "the file is UTF-16 text", "save it as ASCII or UTF-8")
            # errors="replace": a stray byte in the free-text name must not stop the read
            yield io.TextIOWrapper(raw, encoding="utf-8-sig", errors="replace"), label
    else:
        stream_name = getattr(source, "name", None)
        label = name if name is not None else (stream_name if isinstance(stream_name, str) else "<stream>")
        yield source, label


# ---- reading: numbers ---------------------------------------------------------------


def _short(token: str) -> str:
    """A token as messages quote it: a runaway token must not flood the message."""
    return token if len(token) <= 24 else token[:20] + "..."


def _integer(line: _Line, index: int, path: str, what: str, low: int, high: int, hint: str) -> int:
    token = line.tokens[index]
    if not _INT.match(token):
        raise FormatError(path, line.number, line.column(index), f"{what} {_short(token)!r} is not an integer", hint)
    if len(token) > _MAX_TOKEN:  # 4,301 zeros would also trip int()'s digit limit
        raise FormatError(path, line.number, line.column(index),
                          f"{what} {_short(token)} is {len(token):,} characters long, too long for a number in "
                          f"{low}..{high}", hint)
    digits = token.lstrip("+-").lstrip("0") or "0"
    value = int(digits) if len(digits) <= _MAX_INT_DIGITS else None
    if value is not None and token.startswith("-"):
        value = -value
    if value is None or not low <= value <= high:
        raise FormatError(path, line.number, line.column(index),
                          f"{what} {_short(token)} is out of range {low}..{high}", hint)
    return value


def _fps(line: _Line, index: int, path: str) -> float:
    token = line.tokens[index]
    hint = "the third header field is frames per second, e.g. 25 or 29.97"
    if not _FLOAT.match(token) or len(token) > 64:
        raise FormatError(path, line.number, line.column(index), f"frame rate {_short(token)!r} is not a number", hint)
    value = float(token)
    problem = fps_problem(value)
    if problem is not None:
        raise FormatError(path, line.number, line.column(index), problem,
                          "an FBA stream carries 1/16 to 255 15/16 frames per second")
    return value


# ---- reading: records ---------------------------------------------------------------


def _parse_header(line: _Line, path: str) -> FapHeader:
    tokens = line.tokens
    if tokens[0] not in SUPPORTED_VERSIONS:
        raise FormatError(path, line.number, line.column(0),
                          f"unsupported .fap version {_short(tokens[0])!r}",
                          f"the first line must be the header '<version> <name> <fps> <number_of_frames>' "
                          f"with version one of {', '.join(SUPPORTED_VERSIONS)}")
    if len(tokens) < 4:
        raise FormatError(path, line.number, line.column(len(tokens)),
                          f"the header has {len(tokens)} fields, expected 4",
                          "write '<version> <name> <fps> <number_of_frames>', e.g. '2.1 joy.fap 25 108'")
    # Version 2.0: VREng divides its values by 20 (FAPV20_DIV); what that means was never checked,
    # so 2.0 files are read exactly like 2.1 (values as written, in FAPU).
    fps = _fps(line, len(tokens) - 2, path)
    n_frames = _integer(line, len(tokens) - 1, path, "frame count", 0, INT32_MAX,
                        "the last header field is the number of frames, a whole number")
    # the name may contain spaces (Greta: 'AU Interpolation_1111.fap'): it is all between version and fps
    name = line.span_text(1, len(tokens) - 3)
    return FapHeader(tokens[0], name, fps, n_frames)


def _parse_mask(line: _Line, path: str) -> np.ndarray:
    tokens = line.tokens
    for i, token in enumerate(tokens):
        if token != "0" and token != "1":
            raise FormatError(path, line.number, line.column(i),
                              f"mask entry {i + 1} is {_short(token)!r}, expected 0 or 1",
                              "a mask line has one 0/1 per FAP 1..68; check that mask and frame lines alternate")
    if len(tokens) < N_FAPS:
        raise FormatError(path, line.number, line.column(len(tokens)),
                          f"the mask line has {len(tokens)} entries, expected {N_FAPS}",
                          "give one 0/1 entry for each of FAPs 1..68")
    # Greta writes 69 entries: anything after the 68th is ignored
    return np.array([t == "1" for t in tokens[:N_FAPS]], dtype=bool)


def _value_count(mask: np.ndarray) -> int:
    """Integers a frame line carries after its frame number, for this mask."""
    return VISEME_WIDTH * int(mask[0]) + EXPRESSION_WIDTH * int(mask[1]) + int(mask[2:].sum())


def _parse_frame(line: _Line, mask: np.ndarray, mask_line: _Line, previous: int, path: str, fps: float,
                 limit: int) -> FapRecord:
    number = _integer(line, 0, path, "frame number", 0, INT32_MAX,
                      "a frame line starts with its frame number, a whole number >= 0")
    if number >= limit:
        raise FormatError(path, line.number, line.column(0),
                          f"frame number {number:,} lies {number / fps / 3600:,.1f} h into the stream at {fps:g} fps, "
                          f"past the {MAX_SPAN_SECONDS // 3600} h a stream may span",
                          f"frame numbers run below {limit:,} at {fps:g} fps; renumber the frames or "
                          "split the file")
    if number <= previous:
        raise FormatError(path, line.number, line.column(0),
                          f"frame number {number} does not increase (the previous frame is {previous})",
                          "frame numbers must increase; renumber the frames or remove the duplicate")
    expected = _value_count(mask)
    got = len(line.tokens) - 1
    if got != expected:
        raise FormatError(path, line.number, line.column(min(got, expected) + 1),
                          f"frame {number} has {got} values, expected {expected} for the mask at line "
                          f"{mask_line.number}",
                          "give one value per masked FAP, 4 for FAP 1 and 6 for FAP 2, in FAP order")
    ints = [_integer(line, i, path, "value", INT32_MIN, INT32_MAX, "FAP values are whole numbers in FAPU")
            for i in range(1, got + 1)]
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


def _parse(source: Source, name: str | None) -> Iterator[FapHeader | FapRecord]:
    """The one parser: yields the header, then one record per frame, reading line by line."""
    with _open_source(source, name) as (handle, path):
        lines = _LineReader(handle, path)
        header_line = lines.next()
        if header_line is None:
            raise lines.error_at_end("the file has no header",
                                     "start with '<version> <name> <fps> <number_of_frames>', e.g. '2.1 a.fap 25 0'")
        header = _parse_header(header_line, path)
        limit = frame_limit(header.fps)
        yield header
        previous = -1
        while (mask_line := lines.next()) is not None:
            mask = _parse_mask(mask_line, path)
            frame_line = lines.next()
            if frame_line is None:
                raise lines.error_at_end(f"the file ends after the mask line at line {mask_line.number}",
                                         "add its frame line (frame number, then the masked values) "
                                         "or delete the mask line")
            record = _parse_frame(frame_line, mask, mask_line, previous, path, header.fps, limit)
            previous = record.frame_number
            yield record


def iter_fap(source: Source, *, name: str | None = None) -> Iterator[FapRecord]:
    """Yield ``(frame_number, mask, values, viseme, expression)`` per frame, reading lazily.

    Nothing is opened until the first frame is asked for, and only one line is held
    at a time, so long files stream. The header is still checked. ``name`` replaces
    the path in error messages (useful for streams).
    """
    records = _parse(source, name)
    next(records)  # the header
    yield from records  # type: ignore[misc]


def read_fap(source: Source, *, name: str | None = None) -> FapStream:
    """Read a ``.fap`` file (path or text stream) into a :class:`FapStream`.

    Gaps in the frame numbers become ``skip`` on the frame before the gap;
    timestamps are ``frame_number / fps``. The header's frame count is not
    trusted: the frames found are what is returned.
    """
    records = _parse(source, name)
    header = cast(FapHeader, next(records))
    builder = StreamBuilder()
    numbers = array("q")
    for record in cast("Iterator[FapRecord]", records):  # one record at a time: memory is the stream's arrays
        numbers.append(record.frame_number)
        builder.add(fap_mask=record.mask, fap_values=record.values, viseme=record.viseme,
                    expression=record.expression, timestamp=record.frame_number / header.fps)
    stream = builder.build()
    stream.source_fps = header.fps
    if len(numbers) > 1:
        stream.skip[:-1] = np.diff(np.frombuffer(numbers, dtype=np.int64)) - 1
    return stream


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
    label = os.fsdecode(target) if isinstance(target, (str, bytes, os.PathLike)) else _stream_label(target)
    stream = explicit(stream)  # a .fap cannot say "interpolate": FAPs a decoder copies are written out
    fps = float(stream.fps)
    problem = fps_problem(fps)
    if problem is not None:
        raise FormatError(label, 1, None, problem, "set stream.source_fps (or an intra frame rate) to the real rate")
    numbers = _frame_numbers(stream, label, fps)
    _check_high_level(stream, label)
    n_frames = int(numbers[-1]) + 1 if len(numbers) else 0
    header = _format_header(label, _header_name(name, label), version, fps, n_frames)
    if stream.bap_mask.any():
        warnings.warn(f"{int(stream.bap_mask.any(axis=1).sum())} frames carry BAPs (body animation); "
                      ".fap holds face parameters only, so the BAPs are dropped", FormatWarning, stacklevel=2)
    lines = _format_lines(stream, header, numbers)
    if isinstance(target, (str, bytes, os.PathLike)):
        with open(target, "w", encoding="utf-8", newline="") as handle:
            handle.writelines(lines)
    else:
        target.writelines(lines)


def _stream_label(target: IO[str]) -> str:
    stream_name = getattr(target, "name", None)
    return stream_name if isinstance(stream_name, str) else "<stream>"


def _header_name(name: str | None, label: str) -> str:
    """The header's name field: as given, else the target's file name."""
    if name is not None:
        return name
    return (Path(label).name if label != "<stream>" else "") or "stream.fap"


def _format_header(label: str, name: str, version: str, fps: float, n_frames: int) -> str:
    if version not in SUPPORTED_VERSIONS:
        raise FormatError(label, 1, 1, f"cannot write .fap version {version!r}",
                          f"use one of {', '.join(SUPPORTED_VERSIONS)}")
    clean = name.strip()
    if not clean or "\n" in clean or "\r" in clean:
        raise FormatError(label, 1, None, f"header name {name!r} is empty or spans lines",
                          "pass a one-line name, e.g. name='joy.fap'")
    fps_text = str(int(fps)) if fps.is_integer() else f"{fps:g}"
    return f"{version} {clean} {fps_text} {n_frames}"


def _frame_numbers(stream: FapStream, label: str, fps: float) -> np.ndarray:
    """0, then previous + skip[previous] + 1: skipped frames become gaps."""
    skip = np.asarray(stream.skip, dtype=np.int64)
    if len(skip) and skip.min() < 0:
        k = int(np.argmax(skip < 0))
        raise FormatError(label, 2 * k + 3, 1, f"frame {k} has skip {int(skip[k])} < 0",
                          "skip counts frames left out after a frame and cannot be negative")
    numbers = np.concatenate([[0], np.cumsum(skip[:-1] + 1)]) if len(skip) else skip
    if len(numbers) and numbers[-1] >= frame_limit(fps):
        k = int(np.argmax(numbers >= frame_limit(fps)))
        raise FormatError(label, 2 * k + 3, 1, f"frame number {int(numbers[k]):,} is past the "
                          f"{MAX_SPAN_SECONDS // 3600} h a stream may span at {fps:g} fps",
                          "reduce the skip counts or split the stream")
    return numbers.astype(np.int64)


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
        yield " ".join("1" if m else "0" for m in mask.tolist()) + "\n"
        parts = [str(int(numbers[k]))]
        if mask[0]:
            parts += map(str, stream.viseme[k].tolist())
        if mask[1]:
            parts += map(str, stream.expression[k].tolist())
        parts += map(str, stream.fap_values[k, 2:][mask[2:]].tolist())
        yield " ".join(parts) + "\n"
