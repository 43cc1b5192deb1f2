"""The package's one JSON reader: bounded, and every fault at ``path:line:column``.

``json.loads`` alone turns hostile input into tracebacks or unbounded work: 100,000 ``[`` end in a
``RecursionError``, a 5,000-digit integer in a ``ValueError``, ``NaN`` and ``1e999`` pass as floats
nobody can use, bytes that are not UTF-8 in a ``UnicodeDecodeError``. :func:`loads` and
:func:`read_json` check, in this order and each in time linear in the size:

1. size: at most ``max_bytes`` (default :data:`MAX_JSON_BYTES`, 16 MiB), refused before reading more;
2. kind: a file whose first bytes are another format's signature (a PNG, a ZIP...) is named as such
   (:mod:`mpeg4fa.filetype`);
3. encoding: UTF-8 (a byte-order mark is skipped); UTF-16 or a bad byte is located;
4. nesting: at most ``max_depth`` (default :data:`MAX_DEPTH`, 64) levels of ``[`` / ``{``, counted by a
   scan of the brackets outside strings *before* parsing;
5. parsing: ``json`` syntax errors at their line:column; ``NaN``/``Infinity``, numbers beyond a
   double and integers of more than :data:`MAX_INT_DIGITS` digits are refused at theirs.

Errors are made by ``error(path, line, column, problem, hint)``: :class:`JsonError` by default, or
the caller's own located error type with that signature (``FormatError``, ``FdpError``...). The
module sits at the bottom of the package (it imports only :mod:`mpeg4fa.errors` and
:mod:`mpeg4fa.filetype`), so every layer can use it. :class:`LineIndex` turns offsets into
line:column in logarithmic time, for readers that locate many items of one document.
"""
from __future__ import annotations

import json
import math
import os
import re
from bisect import bisect_right
from typing import Any, Callable

import numpy as np

from mpeg4fa.errors import MpegFaError, unreadable
from mpeg4fa.filetype import HEAD_BYTES, refuse_foreign

__all__ = ["JsonError", "MAX_JSON_BYTES", "MAX_DEPTH", "MAX_INT_DIGITS", "loads", "read_json", "decode_utf8",
           "LineIndex", "line_col", "deepest", "loads_lines", "json_text"]

MAX_JSON_BYTES = 16 << 20
"""Default ceiling on a JSON document (16 MiB): parsed JSON takes several times its text in memory."""
MAX_DEPTH = 64
"""Default ceiling on nesting (arrays and objects inside each other); our documents need fewer than 10."""
MAX_INT_DIGITS = 100
"""Longest integer literal read; longer ones are no count or index any of our files holds."""

ErrorFactory = Callable[[str, "int | None", "int | None", str, str], Exception]


class JsonError(MpegFaError, ValueError):
    """A JSON document that cannot be read: ``str()`` is ``path:line:column: problem (hint)``."""

    def __init__(self, path: str, line: int | None, column: int | None, problem: str, hint: str = "") -> None:
        self.path, self.line, self.column, self.problem = path, line, column, problem
        where = path if line is None else f"{path}:{line}" if column is None else f"{path}:{line}:{column}"
        super().__init__(problem, where, hint)

    def __reduce__(self):
        return (type(self), (self.path, self.line, self.column, self.problem, self.hint))


class LineIndex:
    """Offsets of a text's line starts, computed once: :meth:`line_col` is a bisection, not a recount."""

    def __init__(self, text: str) -> None:
        self.text = text
        self._starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def line_col(self, offset: int) -> tuple[int, int]:
        """1-based (line, column) of character ``offset``."""
        line = bisect_right(self._starts, offset)
        return line, offset - self._starts[line - 1] + 1

    def line(self, offset: int) -> int:
        return bisect_right(self._starts, offset)


def line_col(text: str, offset: int) -> tuple[int, int]:
    """1-based (line, column) of character ``offset`` of ``text`` (one lookup; use :class:`LineIndex` for many)."""
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def decode_utf8(raw: bytes, path: str, error: ErrorFactory = JsonError, what: str = "JSON") -> str:
    """``raw`` as text: UTF-8, a leading byte-order mark dropped; UTF-16 or an invalid byte is located."""
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise error(path, 1, 1, f"the file is UTF-16 text, not UTF-8 ({what} is read as UTF-8)", "save the file as UTF-8")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        start = raw.rfind(b"\n", 0, exc.start) + 1
        col = len(raw[start:exc.start].decode("utf-8", "replace")) + 1
        raise error(path, line, col, f"not UTF-8: byte 0x{raw[exc.start]:02x} (byte offset {exc.start}) cannot "
                    "start or continue a character", "save the file as UTF-8") from None
    return text[1:] if text.startswith("\ufeff") else text


def json_text(source: str | bytes, path: str, error: ErrorFactory = JsonError, what: str = "JSON") -> str:
    """Bytes as JSON text: a foreign file (PNG, ZIP...) named by its signature, then :func:`decode_utf8`."""
    if isinstance(source, str):
        return source[1:] if source.startswith("\ufeff") else source
    raw = bytes(source)
    refuse_foreign(raw[:HEAD_BYTES], what, lambda problem, hint: error(path, None, None, problem, hint),
                   allowed=("UTF-16 text",))
    return decode_utf8(raw, path, error, what)


_STRING = re.compile(r'"[^"\\]*+(?:\\(?:.|\Z)[^"\\]*+)*+(?:"|\Z)', re.S)
"""A string, or an unterminated one up to the end: it always matches from a quote, possessively, so a scan
never starts over inside a string (``"\\"\\"...`` unterminated was quadratic)."""
_BRACKETS = {ord("["): 1, ord("{"): 1, ord("]"): -1, ord("}"): -1}


def deepest(text: str, limit: int) -> int | None:
    """Offset of the first bracket nested deeper than ``limit`` outside strings, or None: linear, no parse.

    The common case (not too deep) runs in C and numpy over the text with its strings emptied; only a
    document that is too deep is walked character by character, up to the offending bracket.
    """
    bare = _STRING.sub('""', text)
    codes = np.frombuffer(bare.encode("utf-8", "surrogatepass"), dtype=np.uint8)
    opens = (codes == ord("[")) | (codes == ord("{"))
    closes = (codes == ord("]")) | (codes == ord("}"))
    steps = opens[opens | closes].astype(np.int32) * 2 - 1
    if not len(steps) or int(np.cumsum(steps).max()) <= limit:
        return None
    depth, in_string, escaped = 0, False, False
    for i, ch in enumerate(text):
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            if depth > limit:
                return i
        elif ch in "]}":
            depth -= 1
    return None  # only reachable for an unterminated string the fast scan read past: the parser says where


class _Refused(Exception):
    def __init__(self, literal: str, problem: str) -> None:
        self.literal, self.problem = literal, problem


def _constant(name: str) -> float:
    raise _Refused(name, f"{name} is not a number JSON allows")


def _float(literal: str) -> float:
    value = float(literal)
    if not math.isfinite(value):
        raise _Refused(literal, f"number {literal[:40]} is not finite: beyond what a double holds")
    return value


def _int(literal: str) -> int:
    if len(literal.lstrip("-")) > MAX_INT_DIGITS:
        raise _Refused(literal, f"integer of {len(literal.lstrip('-')):,} digits is longer than {MAX_INT_DIGITS}")
    return int(literal)


def _locate_literal(text: str, literal: str) -> int:
    bare = _STRING.sub(lambda m: " " * len(m.group()), text) if '"' in text else text
    found = re.search(r"(?<![\w.+-])" + re.escape(literal) + r"(?![\w.])", bare)
    return found.start() if found else 0


def loads(source: str | bytes, path: str = "<json>", *, max_bytes: int = MAX_JSON_BYTES,
          max_depth: int = MAX_DEPTH, error: ErrorFactory = JsonError, what: str = "JSON",
          object_pairs_hook: Callable[[list[tuple[str, Any]]], Any] | None = None) -> Any:
    """The JSON value of ``source`` (text or bytes), checked as the module docstring says.

    ``what`` names the document in messages (``"a points file"``); ``path`` is the place errors name.
    """
    text = _checked_text(source, path, max_bytes, max_depth, error, what)
    try:
        return json.loads(text, parse_constant=_constant, parse_float=_float, parse_int=_int,
                          object_pairs_hook=object_pairs_hook)
    except json.JSONDecodeError as exc:
        raise error(path, exc.lineno, exc.colno, f"invalid JSON: {exc.msg}",
                    "check the JSON syntax there" if what == "JSON" else f"{what} is JSON") from None
    except _Refused as exc:
        line, col = line_col(text, _locate_literal(text, exc.literal))
        raise error(path, line, col, exc.problem, "give a finite number in ordinary notation") from None
    except RecursionError:  # a hook nesting deeper than max_depth allowed for (should not happen)
        raise error(path, None, None, "JSON nested too deeply", f"nothing in {what} nests this deep") from None


def loads_lines(source: str | bytes, path: str = "<json>", *, max_bytes: int = MAX_JSON_BYTES,
                max_depth: int = MAX_DEPTH, error: ErrorFactory = JsonError, what: str = "JSON lines"
                ) -> list[tuple[int, Any]]:
    """``(line number, value)`` of each non-blank line of a JSON Lines document (one value a line).

    The same checks as :func:`loads`; the nesting scan runs once over the whole text (lines are parsed in
    order and the first bad one stops the read, so every line before it is balanced).
    """
    text = _checked_text(source, path, max_bytes, max_depth, error, what)
    decoder = json.JSONDecoder(parse_constant=_constant, parse_float=_float, parse_int=_int)
    out = []
    for number, line in enumerate(text.splitlines(), start=1):
        body = line.strip()
        if not body:
            continue
        indent = len(line) - len(line.lstrip())
        try:
            value, end = decoder.raw_decode(body)
        except json.JSONDecodeError as exc:
            raise error(path, number, indent + exc.colno, f"invalid JSON: {exc.msg}",
                        f"{what}: one JSON value a line") from None
        except _Refused as exc:
            raise error(path, number, indent + _locate_literal(body, exc.literal) + 1, exc.problem,
                        "give a finite number in ordinary notation") from None
        if body[end:].strip():
            raise error(path, number, indent + end + 1, "more than one JSON value on the line",
                        f"{what}: one JSON value a line")
        out.append((number, value))
    return out


def _checked_text(source: str | bytes, path: str, max_bytes: int, max_depth: int, error: ErrorFactory,
                  what: str) -> str:
    """Steps 1-4 of the module docstring: the text, sized, of the right kind, UTF-8 and not too deep."""
    size = len(source.encode("utf-8", "surrogatepass")) if isinstance(source, str) else len(source)
    if size > max_bytes:
        raise error(path, None, None, f"{what} of {size:,} bytes is larger than the {max_bytes:,} bytes read",
                    f"is this {what}?")
    text = json_text(source, path, error, what)
    deep = deepest(text, max_depth)
    if deep is not None:
        line, col = line_col(text, deep)
        raise error(path, line, col, f"JSON nested more than {max_depth} levels deep",
                    f"nothing in {what} nests this deep; is this the right file?")
    return text


def read_json(path: str | os.PathLike, *, max_bytes: int = MAX_JSON_BYTES, max_depth: int = MAX_DEPTH,
              error: ErrorFactory = JsonError, what: str = "JSON",
              object_pairs_hook: Callable[[list[tuple[str, Any]]], Any] | None = None) -> Any:
    """:func:`loads` of a file; it is read no further than ``max_bytes`` + 1, and OS errors name it."""
    name = os.fsdecode(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read(max_bytes + 1)
    except OSError as exc:
        raise error(name, None, None, *unreadable(exc)) from None
    if len(raw) > max_bytes:
        raise error(name, None, None, f"{what} is larger than the {max_bytes:,} bytes read", f"is this {what}?")
    return loads(raw, name, max_bytes=max_bytes, max_depth=max_depth, error=error, what=what,
                 object_pairs_hook=object_pairs_hook)


