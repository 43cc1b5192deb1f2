"""The grammar ``.fap`` and ``.bap`` text files share: a header, then pairs of mask line + frame line.

Layout::

    # comment lines, anywhere
    <version> <name> <fps> <number_of_frames>
    <mask line: one 0/1 per parameter>            } repeated
    <frame line: frame number, masked values>     } per frame

Why one module: both formats come from the same programs (VREng reads both with one parser) and
must be read with the same leniency about layout (CRLF, trailing spaces, ``#`` comments, a BOM,
names with spaces) and the same strictness about numbers and limits. What differs, the mask
widths, the values a frame line carries and the words of the messages, stays in
:mod:`mpeg4fa.formats.fap_text` and :mod:`mpeg4fa.formats.bap_text`, which describe themselves
to this module with a :class:`Dialect`. Every problem is a :class:`FormatError` at ``path:line:column``.

This is shared machinery of the two format modules, not part of :mod:`mpeg4fa.formats`' API.
"""
from __future__ import annotations

import io
import os
import re
from array import array
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Callable, Generic, Iterable, Iterator, NamedTuple, Protocol, TypeVar, Union

import numpy as np

from mpeg4fa.fba.limits import MAX_SPAN_SECONDS, fps_problem, frame_limit
from mpeg4fa.fba.stacking import StreamBuilder
from mpeg4fa.fba.stream import FapStream, narrowed
from mpeg4fa.formats.errors import FormatError

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1

Source = Union[str, "os.PathLike[str]", IO[str]]
Target = Union[str, "os.PathLike[str]", IO[str]]

_TOKEN = re.compile(r"\S+")
_INT = re.compile(r"[+-]?[0-9]+\Z")
_FLOAT = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\Z")
_MAX_INT_DIGITS = 12  # longer than any int32, short enough for int() to stay cheap and safe
_MAX_TOKEN = 24
"""Longest number token read; an int32 with sign takes 11 characters, a few leading zeros are tolerated."""
MAX_LINE_CHARS = 1 << 16
"""Longest line read (65,536 characters): a frame line of all 68 FAPs takes about 1,000."""
_UTF16_BOMS = (b"\xff\xfe", b"\xfe\xff")
_HEADER_FIELDS = "'<version> <name> <fps> <number_of_frames>'"


class Header(NamedTuple):
    """The header line. ``n_frames`` is what the writer claimed; readers do not rely on it."""

    version: str
    name: str
    fps: float
    n_frames: int


class _Record(Protocol):
    @property
    def frame_number(self) -> int: ...


H = TypeVar("H", bound=Header)
R = TypeVar("R", bound=_Record)


# ---- lines --------------------------------------------------------------------------


class Line:
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


class LineReader:
    """Skips blank and ``#`` lines, and counts lines so that end-of-file errors can say where.

    ``suffix`` (``.fap``, ``.bap``) names the kind of file in the messages."""

    def __init__(self, handle: Iterable[str | bytes], path: str, suffix: str) -> None:
        self._lines = _bounded_lines(handle)
        self.path = path
        self.suffix = suffix
        self.count = 0

    def next(self) -> Line | None:
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
                return Line(self.count, text.rstrip("\r\n"))

    def _check_text(self, text: str) -> None:
        if len(text) > MAX_LINE_CHARS:
            raise FormatError(self.path, self.count, None, f"line is longer than {MAX_LINE_CHARS:,} characters",
                              f"a {self.suffix} line holds the header, a mask or one frame; "
                              f"is this a {self.suffix} file?")
        nul = text.find("\x00")
        if nul >= 0:
            raise FormatError(self.path, self.count, nul + 1, f"NUL byte: this is not a text {self.suffix} file",
                              "an .fba stream is read by decode() or read_stream(); UTF-16 text must be saved "
                              "as UTF-8")

    def error_at_end(self, problem: str, hint: str) -> FormatError:
        return FormatError(self.path, self.count + 1, None, problem, hint)


@contextmanager
def open_source(source: Source, name: str | None) -> Iterator[tuple[Iterable[str], str]]:
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
        yield source, name if name is not None else target_label(source)


# ---- numbers ------------------------------------------------------------------------


def short(token: str) -> str:
    """A token as messages quote it: a runaway token must not flood the message."""
    return token if len(token) <= 24 else token[:20] + "..."


def integer(line: Line, index: int, path: str, what: str, low: int, high: int, hint: str) -> int:
    """Token ``index`` as an integer in ``low..high``, or a located error naming it ``what``."""
    token = line.tokens[index]
    if not _INT.match(token):
        raise FormatError(path, line.number, line.column(index), f"{what} {short(token)!r} is not an integer", hint)
    if len(token) > _MAX_TOKEN:  # 4,301 zeros would also trip int()'s digit limit
        raise FormatError(path, line.number, line.column(index),
                          f"{what} {short(token)} is {len(token):,} characters long, too long for a number in "
                          f"{low}..{high}", hint)
    digits = token.lstrip("+-").lstrip("0") or "0"
    value = int(digits) if len(digits) <= _MAX_INT_DIGITS else None
    if value is not None and token.startswith("-"):
        value = -value
    if value is None or not low <= value <= high:
        raise FormatError(path, line.number, line.column(index),
                          f"{what} {short(token)} is out of range {low}..{high}", hint)
    return value


def _fps(line: Line, index: int, path: str) -> float:
    token = line.tokens[index]
    hint = "the third header field is frames per second, e.g. 25 or 29.97"
    if len(token) > 64 or not _FLOAT.match(token):
        raise FormatError(path, line.number, line.column(index), f"frame rate {short(token)!r} is not a number", hint)
    value = float(token)
    problem = fps_problem(value)
    if problem is not None:
        raise FormatError(path, line.number, line.column(index), problem,
                          "an FBA stream carries 1/16 to 255 15/16 frames per second")
    return value


# ---- the format's description -------------------------------------------------------


@dataclass(frozen=True)
class Dialect(Generic[H, R]):
    """What a format adds to the shared grammar: its versions, its words, and how it reads a mask and a frame.

    ``header`` builds the format's header from (version, name, fps, claimed frame count);
    ``mask(line, path)`` reads a mask line; ``frame(line, mask, mask_line, previous, path, fps, limit)``
    reads the frame line that follows it. ``other_versions`` are versions of the sibling format,
    answered with ``other_hint`` (formatted with ``version``) instead of the list of versions.
    """

    suffix: str
    versions: tuple[str, ...]
    default_version: str
    example_name: str
    header: Callable[[str, str, float, int], H]
    mask: Callable[[Line, str], np.ndarray]
    frame: Callable[[Line, np.ndarray, Line, int, str, float, int], R]
    other_versions: tuple[str, ...] = ()
    other_hint: str = ""


# ---- records ------------------------------------------------------------------------


def _parse_header(line: Line, path: str, dialect: Dialect[H, R]) -> H:
    tokens = line.tokens
    if tokens[0] not in dialect.versions:
        hint = (dialect.other_hint.format(version=tokens[0]) if tokens[0] in dialect.other_versions else
                f"the first line must be the header {_HEADER_FIELDS} "
                f"with version one of {', '.join(dialect.versions)}")
        raise FormatError(path, line.number, line.column(0),
                          f"unsupported {dialect.suffix} version {short(tokens[0])!r}", hint)
    if len(tokens) < 4:
        raise FormatError(path, line.number, line.column(len(tokens)),
                          f"the header has {len(tokens)} fields, expected 4",
                          f"write {_HEADER_FIELDS}, e.g. '{dialect.default_version} {dialect.example_name} 25 108'")
    fps = _fps(line, len(tokens) - 2, path)
    n_frames = integer(line, len(tokens) - 1, path, "frame count", 0, INT32_MAX,
                       "the last header field is the number of frames, a whole number")
    # the name may contain spaces (Greta: 'AU Interpolation_1111.fap'): it is all between version and fps
    return dialect.header(tokens[0], line.span_text(1, len(tokens) - 3), fps, n_frames)


def mask_entries(line: Line, path: str, per: str) -> list[bool]:
    """The 0/1 entries of a mask line (``per`` says what one entry stands for, in the hint)."""
    for i, token in enumerate(line.tokens):
        if token != "0" and token != "1":
            raise FormatError(path, line.number, line.column(i),
                              f"mask entry {i + 1} is {short(token)!r}, expected 0 or 1",
                              f"a mask line has one 0/1 per {per}; check that mask and frame lines alternate")
    return [t == "1" for t in line.tokens]


def frame_number(line: Line, path: str, previous: int, fps: float, limit: int,
                 past: str = f"past the {MAX_SPAN_SECONDS // 3600} h a stream may span") -> int:
    """The frame line's number: a whole number above ``previous`` and below ``limit``."""
    number = integer(line, 0, path, "frame number", 0, INT32_MAX,
                     "a frame line starts with its frame number, a whole number >= 0")
    if number >= limit:
        raise FormatError(path, line.number, line.column(0),
                          f"frame number {number:,} lies {number / fps / 3600:,.1f} h into the stream at {fps:g} fps, "
                          f"{past}",
                          f"frame numbers run below {limit:,} at {fps:g} fps; renumber the frames or split the file")
    if number <= previous:
        raise FormatError(path, line.number, line.column(0),
                          f"frame number {number} does not increase (the previous frame is {previous})",
                          "frame numbers must increase; renumber the frames or remove the duplicate")
    return number


def frame_values(line: Line, path: str, number: int, expected: int, mask_line: Line, count_hint: str,
                 value_hint: str) -> list[int]:
    """The ``expected`` int32 values after the frame number (as many as the mask at ``mask_line`` asks)."""
    got = len(line.tokens) - 1
    if got != expected:
        raise FormatError(path, line.number, line.column(min(got, expected) + 1),
                          f"frame {number} has {got} values, expected {expected} for the mask at line "
                          f"{mask_line.number}", count_hint)
    return [integer(line, i, path, "value", INT32_MIN, INT32_MAX, value_hint) for i in range(1, got + 1)]


def parse(source: Source, name: str | None, dialect: Dialect[H, R]) -> Iterator[H | R]:
    """The one parser: yields the header, then one record per frame, reading line by line."""
    with open_source(source, name) as (handle, path):
        lines = LineReader(handle, path, dialect.suffix)
        header_line = lines.next()
        if header_line is None:
            raise lines.error_at_end("the file has no header",
                                     f"start with {_HEADER_FIELDS}, e.g. "
                                     f"'{dialect.default_version} a{dialect.suffix} 25 0'")
        header = _parse_header(header_line, path, dialect)
        fps = header.fps
        limit = frame_limit(fps)
        yield header
        previous = -1
        while (mask_line := lines.next()) is not None:
            mask = dialect.mask(mask_line, path)
            frame_line = lines.next()
            if frame_line is None:
                raise lines.error_at_end(f"the file ends after the mask line at line {mask_line.number}",
                                         "add its frame line (frame number, then the masked values) "
                                         "or delete the mask line")
            record = dialect.frame(frame_line, mask, mask_line, previous, path, fps, limit)
            previous = record.frame_number
            yield record


def build_stream(records: Iterable[R], fps: float, add: Callable[[StreamBuilder, R, float], None]) -> FapStream:
    """A :class:`FapStream` from records, one at a time (memory is the stream's arrays).

    ``add(builder, record, timestamp)`` adds one frame; timestamps are ``frame_number / fps`` and gaps
    in the frame numbers become ``skip`` on the frame before the gap."""
    builder = StreamBuilder()
    numbers = array("q")
    for record in records:
        numbers.append(record.frame_number)
        add(builder, record, record.frame_number / fps)
    stream = builder.build()
    stream.source_fps = fps
    if len(numbers) > 1:  # a new array: the builder's may be too narrow for the gaps (fba.stream.STORAGE)
        skip = np.zeros(len(numbers), dtype=np.int64)
        skip[:-1] = np.diff(np.frombuffer(numbers, dtype=np.int64)) - 1
        stream.skip = narrowed(skip, "skip")
    return stream


# ---- writing ------------------------------------------------------------------------


def target_label(target: Source) -> str:
    """How messages name a path or a text stream."""
    if isinstance(target, (str, bytes, os.PathLike)):
        return os.fsdecode(target)
    stream_name = getattr(target, "name", None)
    return stream_name if isinstance(stream_name, str) else "<stream>"


def stream_fps(stream: FapStream, label: str) -> float:
    """The rate the header will carry, refused when an FBA intra header could not carry it."""
    fps = float(stream.fps)
    problem = fps_problem(fps)
    if problem is not None:
        raise FormatError(label, 1, None, problem, "set stream.source_fps (or an intra frame rate) to the real rate")
    return fps


def frame_numbers(stream: FapStream, label: str, fps: float) -> np.ndarray:
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


def check_version(label: str, suffix: str, versions: tuple[str, ...], version: str) -> None:
    """A version the writer may put in the header, else a located error."""
    if version not in versions:
        raise FormatError(label, 1, 1, f"cannot write {suffix} version {version!r}",
                          f"use one of {', '.join(versions)}")


def header_name(name: str | None, label: str, suffix: str) -> str:
    """The header's name field: as given, else the target's file name (``stream.fap`` for a nameless stream)."""
    if name is not None:
        return name
    return (Path(label).name if label != "<stream>" else "") or f"stream{suffix}"


def header_text(label: str, name: str, example_name: str, version: str, fps: float, n_frames: int) -> str:
    """The header line (without its line end); ``name`` must fit on one line."""
    clean = name.strip()
    if not clean or "\n" in clean or "\r" in clean:
        raise FormatError(label, 1, None, f"header name {name!r} is empty or spans lines",
                          f"pass a one-line name, e.g. name={example_name!r}")
    fps_text = str(int(fps)) if fps.is_integer() else f"{fps:g}"
    return f"{version} {clean} {fps_text} {n_frames}"


def mask_text(mask: np.ndarray) -> str:
    """A mask line, with its line end."""
    return " ".join("1" if m else "0" for m in mask.tolist()) + "\n"


def frame_text(number: int, values: Iterable[int]) -> str:
    """A frame line, with its line end: the frame number, then the masked values."""
    return " ".join([str(number), *map(str, values)]) + "\n"


def write_lines(target: Target, lines: Iterable[str]) -> None:
    """Write the lines to a path (UTF-8, ``\\n`` line ends as given) or to a text stream."""
    if isinstance(target, (str, bytes, os.PathLike)):
        with open(target, "w", encoding="utf-8", newline="") as handle:
            handle.writelines(lines)
    else:
        target.writelines(lines)
