r"""Inline expression tags in the text that the encoder speaks: ``(joy, 40, 0.5) Hello``.

The encoder needs two things from the tagged text: the plain text for the speech
engine, and for each tag the place in that plain text where it stood, because a
tag's start time is the speech time at that character. So :func:`parse_markup`
removes the tags and returns each one with its character offset.

Grammar (``WS`` is any run of characters for which ``str.isspace()`` is true)::

    markup     := ( text | escape | tag )*
    escape     := "\(" | "\)" | "\\"          -- a literal "(", ")" or "\"
    tag        := "(" WS? expression WS? "," WS? intensity WS? "," WS? seconds WS? ")"
    expression := word                         -- case-insensitive, a known expression
    intensity  := ["+" | "-"] [0-9]+           -- must lie in 0..63; 0 resets to neutral
    seconds    := ["+" | "-"] ( [0-9]+ ["." [0-9]*] | "." [0-9]+ )   -- must be >= 0
    word       := a letter or "_", then letters, digits or "_" (Unicode, as in regex \w)

Which parentheses are tags: an unescaped ``(`` starts a tag (and must then be one,
or it is an error, with its line and column) when what follows it, after optional
whitespace, is

1. a known expression name as a whole word, not followed (after whitespace) by a
   letter: ``(joy, 40, 0.5)``, but also ``(joy 40 0.5)`` (missing commas), ``(Joy)``,
   ``(anger, 99, 1)``; while ``(joy is contagious)`` is prose; or
2. the whole shape of a tag: a word, a number and a number, comma-separated:
   ``(jyo, 40, 0.5)`` (an unknown expression), ``(smile, 20, 1)``; or a word that is
   nearly an expression's name (difflib ratio >= 0.7), a comma and a number:
   ``(joyy, 40)``, ``(suprise, 30)``; or
3. nothing but whitespace before its ``)``: an empty tag.

Every other parenthesis is ordinary text, so ``(see below)``, ``(Paris, France)``,
``(however, we think)``, ``(Smith, 2020)``, ``(3, 4)`` and a stray ``)`` are spoken as
written; so is a prose parenthesis that has the whole shape of a tag
(``(Smith, 2020, 12)``) if its ``(`` is written ``\(``. A tag ends at the first ``)``; reaching a ``(`` or the end of the
text first means it is unclosed. A tag may span lines. A backslash before any
other character is an ordinary backslash.

``lenient=True`` speaks a malformed tag as the text it is (from its ``(``), and says
so once: one :class:`~mpeg4fa.speech.errors.MarkupWarning` naming the first one's
place and what was wrong, and how many there were (:attr:`Markup.malformed` lists them).

Whitespace rule (offsets refer to the text after it is applied):

* a tag, together with the whitespace touching it and any further tags in that
  run, is a *gap*; the gap becomes one space " " if it contained whitespace and
  lies between two pieces of text, and nothing otherwise (so ``word(joy,9,1)word``
  stays ``wordword``, which is right for Chinese, where words are not spaced);
* a gap at the start or end of the text becomes nothing, and leading and trailing
  whitespace of the whole text is trimmed;
* all other whitespace is kept as written, so text without tags parses to
  itself, stripped.

Each tag's offset is that of the first character spoken after it, i.e. where
the gap ended in the plain text (``len(text)`` for tags at the end); tags in the
same gap share one offset. Line breaks are ``\n``, ``\r\n`` and a lone ``\r``;
lines and columns are 1-based and count characters (a tab is one column).
"""
from __future__ import annotations

import difflib
import math
import re
import warnings
from bisect import bisect_right
from collections.abc import Iterable
from dataclasses import dataclass

from mpeg4fa.spec import HIGH_LEVEL_FIELDS
from mpeg4fa.spec.profiles import EXPRESSION_PROFILES
from mpeg4fa.speech.errors import MarkupError, MarkupWarning

__all__ = ["Tag", "Markup", "parse_markup", "INTENSITY_MIN", "INTENSITY_MAX"]

_INTENSITY = next(f for f in HIGH_LEVEL_FIELDS if f.fap == 2 and f.field == "intensity1")
INTENSITY_MIN: int = _INTENSITY.i_min
"""Lowest tag intensity (0: neutral), FAP 2's intensity range so a tag always fits the stream."""
INTENSITY_MAX: int = _INTENSITY.i_max
"""Highest tag intensity (63: the full expression)."""

MAX_TEXT_CHARS = 200_000
"""Longest text read (about 3 h of speech at 175 words a minute): the speech, its audio (silence too,
for the estimate engine) and the frames grow with it, so a longer text is refused, not half-spoken."""

_WORD = re.compile(r"[^\W\d]\w*")
_SHAPE = re.compile(r"\(\s*[^\W\d]\w*\s*,\s*[+-]?\.?[0-9][^,()]*,\s*[+-]?\.?[0-9]")
"""A ``(`` that starts a tag by its whole shape: a word, a comma, a number, a comma, a number."""
_NEAR_SHAPE = re.compile(r"\(\s*([^\W\d]\w*)\s*,\s*[+-]?\.?[0-9]")
"""A ``(`` with a word, a comma and a number: a tag when the word is nearly an expression's name."""
_NEAR = 0.7
"""How alike (difflib's ratio) a word must be to an expression's name for ``(word, number`` to be a tag."""
_NOT_A_LETTER_NEXT = r"\b(?!\s*[^\W\d_])"
_EMPTY = re.compile(r"\(\s*\)")
_PAREN = re.compile(r"[()]")
_LINE_BREAK = re.compile(r"\r\n|\r|\n")
_INTEGER = re.compile(r"([+-]?)([0-9]+)")
_DECIMAL = re.compile(r"([+-]?)([0-9]+(?:\.[0-9]*)?|\.[0-9]+)")
_ESCAPABLE = "()\\"
_EXAMPLE = "(joy, 40, 0.5)"
_LITERAL_HINT = r"write \( for a literal parenthesis"
_QUOTE_MAX = 24


def _quote(text: str) -> str:
    """The offending part for a message, cut short so a runaway tag does not flood it."""
    return repr(text if len(text) <= _QUOTE_MAX else text[:_QUOTE_MAX] + "...")


@dataclass(frozen=True)
class Tag:
    """One expression change: reach ``intensity`` of ``expression`` in ``seconds``, from ``offset`` on."""

    expression: str
    """Lower-case expression name."""
    intensity: int
    """Target intensity 0..63 (0: back to neutral)."""
    seconds: float
    """Time to reach the intensity, >= 0."""
    offset: int
    """Character offset in :attr:`Markup.text` of the first character spoken after the tag."""
    line: int
    """1-based line of the tag's ``(`` in the source, for messages."""
    column: int
    """1-based column of the tag's ``(`` in the source."""


@dataclass(frozen=True)
class Markup:
    """Tagged text taken apart: what to speak and, in source order, when the face changes."""

    text: str
    tags: tuple[Tag, ...]
    name: str = "<text>"
    """Where the text came from (a file name), as used in error messages."""
    places: tuple[tuple[int, int], ...] = ()
    """(line, column) in the source of each character of :attr:`text` (1-based), for errors about it."""
    malformed: tuple[MarkupError, ...] = ()
    """Under ``lenient``: the malformed tags spoken as text, each as the error it would have been."""

    def place(self, index: int) -> tuple[int, int]:
        """Source (line, column) of ``text[index]``; counted in ``text`` itself for a Markup made by hand."""
        if 0 <= index < len(self.places):
            return self.places[index]
        from mpeg4fa.speech.script import line_column
        return line_column(self.text, index)


class _Positions:
    """Index -> (line, column), 1-based, so errors can name the place the user sees in an editor."""

    def __init__(self, source: str) -> None:
        self._starts = [0] + [m.end() for m in _LINE_BREAK.finditer(source)]

    def __call__(self, index: int) -> tuple[int, int]:
        line = bisect_right(self._starts, index)
        return line, index - self._starts[line - 1] + 1


_NOT_TEXT = re.compile("[\0\ud800-\udfff]")
"""What a ``str`` may hold but no text is: NUL, and a lone UTF-16 surrogate (U+D800..U+DFFF), which no UTF-8
writer (a speech engine's input, a timings file) can encode."""


def check_characters(source: str, name: str = "<text>") -> None:
    """MarkupError at the first NUL or lone surrogate of ``source`` (see :data:`_NOT_TEXT`), else nothing.

    The parse pass is the one door every text goes through (a command's argument, a file, standard input, a
    library caller's string), so no engine sees such a character. Python puts a byte that is not UTF-8 in
    a command line as a surrogate U+DC80..U+DCFF (``surrogateescape``): that byte is named.
    """
    found = _NOT_TEXT.search(source)
    if found is None:
        return
    char = found.group()
    line, column = _Positions(source)(found.start())
    if char == "\0":
        raise MarkupError("a NUL character (U+0000) is no text to speak", line, column,
                          "remove it; a binary file is no text", name)
    code = ord(char)
    if 0xDC80 <= code <= 0xDCFF:
        problem = f"not a character: byte 0x{code - 0xDC00:02x} is not UTF-8 (it came as U+{code:04X})"
        hint = "give the text as UTF-8"
    else:
        problem = f"not a character: U+{code:04X} is half of a UTF-16 surrogate pair"
        hint = "remove it, or write the character the pair stood for"
    raise MarkupError(problem, line, column, hint, name)


class _Parser:
    """One pass over the source; builds the plain text character by character.

    Characters go to a list so that an offset is simply its length; whitespace
    next to tags is held back until it is known whether text follows.
    """

    def __init__(self, source: str, known: tuple[str, ...], name: str, lenient: bool = False) -> None:
        self.source, self.known, self.name, self.lenient = source, known, name, lenient
        self.malformed: list[MarkupError] = []
        names = "|".join(re.escape(n) for n in sorted(known, key=len, reverse=True))
        self.known_head = re.compile(rf"\(\s*(?:{names}){_NOT_A_LETTER_NEXT}", re.IGNORECASE) if known else None
        self.where = _Positions(source)
        self.out: list[str] = []
        self.places: list[tuple[int, int]] = []  # source (line, column) of each character of out
        self.tags: list[Tag] = []
        self.pending: list[tuple[str, int, float, int]] = []
        """Tags of the current gap: (expression, intensity, seconds, source index)."""
        self.gap_space = False

    def error(self, index: int, message: str, hint: str) -> MarkupError:
        line, column = self.where(index)
        return MarkupError(message, line, column, hint, self.name)

    # -- building the plain text ------------------------------------------------------------------

    def emit(self, char: str, index: int, literal: bool = False) -> None:
        space = not literal and char.isspace()
        if space and self.pending:
            self.gap_space = True
        elif space and not self.out:
            return  # leading whitespace is trimmed
        else:
            self.flush(separate=True, at=index)
            self.out.append(char)
            self.places.append(self.where(index))

    def pop_space(self) -> None:
        self.out.pop()
        self.places.pop()

    def add_tag(self, expression: str, intensity: int, seconds: float, index: int) -> None:
        while self.out and self.out[-1].isspace():
            self.pop_space()
            self.gap_space = True
        self.pending.append((expression, intensity, seconds, index))

    def flush(self, separate: bool, at: int = 0) -> None:
        if not self.pending:
            return
        if separate and self.gap_space and self.out:
            self.out.append(" ")
            self.places.append(self.where(at))
        offset = len(self.out)
        for expression, intensity, seconds, index in self.pending:
            line, column = self.where(index)
            self.tags.append(Tag(expression, intensity, seconds, offset, line, column))
        self.pending.clear()
        self.gap_space = False

    def finish(self) -> Markup:
        while self.out and self.out[-1].isspace():
            self.pop_space()
        self.flush(separate=False)
        return Markup("".join(self.out), tuple(self.tags), self.name, tuple(self.places), tuple(self.malformed))

    # -- reading the source -----------------------------------------------------------------------

    def is_tag(self, i: int) -> bool:
        """Whether the ``(`` at ``i`` starts a tag (see the module docstring: a known name, or the shape)."""
        if _SHAPE.match(self.source, i) or (self.known_head and self.known_head.match(self.source, i)):
            return True
        near = _NEAR_SHAPE.match(self.source, i)
        return bool(near and difflib.get_close_matches(near.group(1).lower(), self.known, n=1, cutoff=_NEAR))

    def run(self) -> Markup:
        source, i, n = self.source, 0, len(self.source)
        while i < n:
            char = source[i]
            if char == "\\" and i + 1 < n and source[i + 1] in _ESCAPABLE:
                self.emit(source[i + 1], i, literal=True)
                i += 2
            elif char == "(" and (_EMPTY.match(source, i) or self.is_tag(i)):
                try:
                    if _EMPTY.match(source, i):
                        raise self.error(i, "empty tag", f"write a tag as {_EXAMPLE}, or {_LITERAL_HINT}")
                    i = self.tag(i)
                except MarkupError as exc:
                    if not self.lenient:
                        raise
                    self.malformed.append(exc)  # spoken as written, from its "("
                    self.emit(char, i)
                    i += 1
            else:
                self.emit(char, i)
                i += 1
        return self.finish()

    def tag(self, start: int) -> int:
        """Reads the tag whose ``(`` is at ``start``; returns the index after its ``)``."""
        close = _PAREN.search(self.source, start + 1)
        if close is None or close.group() == "(":
            before = "the end of the text" if close is None else "the next '('"
            raise self.error(start, f"tag is not closed before {before}",
                             f"end the tag with ')', as in {_EXAMPLE}, or {_LITERAL_HINT}")
        end = close.start()
        commas = [start]  # the "(" stands before part 0 as each comma before the part after it
        while (comma := self.source.find(",", commas[-1] + 1, end)) != -1:
            commas.append(comma)
        delimiters = [*commas[1:], end]
        parts = [self.strip(comma + 1, stop) for comma, stop in zip(commas, delimiters)]
        expression = self.expression(*parts[0])
        if len(parts) < 2:
            raise self.error(end, "tag has 1 part, needs 3: missing intensity",
                             f"write (expression, intensity, seconds), as in {_EXAMPLE}")
        intensity = self.intensity(*parts[1], delimiter=delimiters[1])
        if len(parts) < 3:
            raise self.error(end, f"tag has {len(parts)} parts, needs 3: missing T (seconds)",
                             f"add the time to reach the intensity, as in {_EXAMPLE}")
        seconds = self.seconds(*parts[2], delimiter=delimiters[2])
        if len(parts) > 3:
            raise self.error(commas[3], f"tag has {len(parts)} parts, needs 3",
                             f"write (expression, intensity, seconds), as in {_EXAMPLE}")
        self.add_tag(expression, intensity, seconds, start)
        return end + 1

    def one_token(self, start: int, stop: int, token_end: int) -> None:
        """A part holds one thing: anything after it (past ``token_end``) is a missing comma."""
        rest = self.source[token_end:stop]
        if not rest:
            return
        gap = len(rest) - len(rest.lstrip())
        if gap:
            raise self.error(token_end + gap, f"missing ',' after {_quote(self.source[start:token_end])}",
                             f"separate the parts with commas, as in {_EXAMPLE}")
        raise self.error(token_end, f"unexpected {_quote(rest)} after {_quote(self.source[start:token_end])}",
                         f"write (expression, intensity, seconds), as in {_EXAMPLE}")

    def token_end(self, start: int, stop: int) -> int:
        """Where the part's first whitespace-separated token ends."""
        text = self.source[start:stop]
        cut = next((k for k, c in enumerate(text) if c.isspace()), len(text))
        return start + cut

    def strip(self, start: int, stop: int) -> tuple[int, int]:
        """Source bounds of a part without the whitespace around it."""
        text = self.source[start:stop]
        lead = len(text) - len(text.lstrip())
        return start + lead, start + len(text.rstrip())

    def expression(self, start: int, stop: int) -> str:
        word_match = _WORD.match(self.source, start, stop)
        if word_match is None:  # cannot happen for a "(" that is_tag() took; kept for a clear message
            raise self.error(start, "a tag starts with an expression name", f"write {_EXAMPLE}, or {_LITERAL_HINT}")
        word, name = word_match.group(), word_match.group().lower()
        if name in self.known:
            self.one_token(start, stop, word_match.end())
            return name
        close = difflib.get_close_matches(name, self.known, n=1)
        guess = f"did you mean {close[0]!r}? " if close else ""
        known = ", ".join(self.known) if self.known else "(none)"
        raise self.error(start, f"unknown expression {_quote(word)}",
                         f"{guess}known expressions: {known}; or {_LITERAL_HINT}")

    def intensity(self, start: int, stop: int, delimiter: int) -> int:
        value = self.integer(start, self.token_end(start, stop), delimiter)
        self.one_token(start, stop, self.token_end(start, stop))
        return value

    def integer(self, start: int, stop: int, delimiter: int) -> int:
        text = self.source[start:stop]
        hint = f"write a whole number from {INTENSITY_MIN} (neutral) to {INTENSITY_MAX} (full), " \
               f"as in {_EXAMPLE}"
        if not text:
            raise self.error(delimiter, "missing intensity", hint)
        match = _INTEGER.fullmatch(text)
        if match is None:
            raise self.error(start, f"intensity {_quote(text)} is not an integer", hint)
        digits = match.group(2).lstrip("0") or "0"
        # Compare long digit strings without int(): int() refuses very long ones.
        value = int(digits) if len(digits) <= 6 else INTENSITY_MAX + 1
        if match.group(1) == "-":
            value = -value
        if not INTENSITY_MIN <= value <= INTENSITY_MAX:
            raise self.error(
                start, f"intensity {_quote(text)} is out of range {INTENSITY_MIN}..{INTENSITY_MAX}", hint)
        return value

    def seconds(self, start: int, stop: int, delimiter: int) -> float:
        value = self.decimal(start, self.token_end(start, stop), delimiter)
        self.one_token(start, stop, self.token_end(start, stop))
        return value

    def decimal(self, start: int, stop: int, delimiter: int) -> float:
        text = self.source[start:stop]
        hint = f"write the time to reach the intensity in seconds, e.g. 0.5, 1 or .25, as in {_EXAMPLE}"
        if not text:
            raise self.error(delimiter, "missing T (seconds)", hint)
        match = _DECIMAL.fullmatch(text)
        if match is None:
            raise self.error(start, f"T {_quote(text)} is not a number", hint)
        value = float(match.group(2))
        if match.group(1) == "-" and value != 0.0:
            raise self.error(start, f"T {_quote(text)} is negative", "a time cannot be negative: " + hint)
        if not math.isfinite(value):
            raise self.error(start, f"T {_quote(text)} is too large", hint)
        return value + 0.0


def parse_markup(source: str, *, expressions: Iterable[str] | None = None, name: str = "<text>",
                 lenient: bool = False) -> Markup:
    """Split tagged text into the plain text to speak and its tags (see the module docstring).

    ``expressions`` are the names a tag may use, matched case-insensitively;
    by default those of :data:`~mpeg4fa.spec.profiles.EXPRESSION_PROFILES`, so
    an expression added to ``expression_faps.csv`` can be tagged at once.
    ``name`` labels error messages. Raises :class:`MarkupError` (with line,
    column and a hint) for a malformed tag or a character no text holds (NUL, a
    lone surrogate: :func:`check_characters`), and nothing else for any text;
    with ``lenient``, malformed tags are spoken as text and said in one
    :class:`MarkupWarning` (the text's length bound and the characters still raise).
    """
    if len(source) > MAX_TEXT_CHARS:
        line, column = _Positions(source)(MAX_TEXT_CHARS)
        raise MarkupError(f"the text is {len(source):,} characters long, more than the {MAX_TEXT_CHARS:,} "
                          "read at once", line, column, "split it and encode the parts one after another", name)
    check_characters(source, name)
    names = EXPRESSION_PROFILES if expressions is None else expressions
    known = tuple(dict.fromkeys(str(n).lower() for n in names))
    markup = _Parser(source, known, name, lenient).run()
    if markup.malformed:
        first, n = markup.malformed[0], len(markup.malformed)
        warnings.warn(f"{first.where}: {n} malformed tag{'s' if n != 1 else ''} spoken as text (lenient); "
                      f"the first: {first.message}", MarkupWarning, stacklevel=2)
    return markup
