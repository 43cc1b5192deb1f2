"""The parse pass: tagged text -> chunks of whole sentences, each a :class:`~.markup.Markup` of its own.

Why: a long text is spoken, timed and coded chunk by chunk, so that memory stays that of a chunk
(the audio, events and frames of the whole text grow with it: 200 kB of text is 3.6 hours of
speech). A chunk is as many whole sentences as fit in :data:`CHUNK_CHARS` characters of plain text,
so a short text is one chunk and is spoken exactly as before. A sentence longer than that is cut
after a clause (``,`` ``;`` ``:``) or between words, and a run of letters longer than that (one
"word" of 60,000 letters) between letters: it is spoken in pieces, as any text speaks. The tags
go with the chunk whose text follows them, with their offsets, lines and columns.

A source longer than the parser reads at once (:data:`~.markup.MAX_TEXT_CHARS`) is parsed in
pieces cut between sentences outside any parenthesis, and an error in a piece is located in the
whole source.
"""
from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterator
from dataclasses import replace

from mpeg4fa.speech.errors import MarkupError
from mpeg4fa.speech.markup import MAX_TEXT_CHARS, Markup, parse_markup

MAX_SOURCE_CHARS = 1 << 20
"""Most characters of text a command reads (1 Mi, about 15 h of English speech): the streaming encoder holds
a chunk at a time, so this bounds only the source string itself (at most 4 MiB of UTF-8) and the work."""

CHUNK_CHARS = 2000
"""Most characters of plain text spoken at once (about two minutes of speech at 175 words a minute)."""
MAX_RUN = 128
"""Longest run without white space spoken at once (the longest English words are under 50 letters): espeak-ng
1.52 overruns a buffer on about 200 single letters run together with dots ('a.a.a...', 400 characters: stack
smashing, found by the fuzz campaign), so a longer run is cut, between characters, into chunks of its own."""
_LONG_RUN = re.compile(rf"\S{{{MAX_RUN + 1},}}")


def long_run(text: str) -> re.Match[str] | None:
    """The first run without white space longer than :data:`MAX_RUN` in ``text`` (None if none): what espeak-ng is
    never handed, for text spoken whole (a transcript, a direct call) rather than cut in chunks."""
    return _LONG_RUN.search(text)

_SENTENCE_END = re.compile(r"[.!?\u2026]+[\"'\u201d\u2019\u00bb)\]]*(?=\s)|[\u3002\uff01\uff1f]+[\u201d\u2019\u300d\u300f\uff09]*"
                           r"|\n[^\S\n]*\n")
"""Where a sentence ends: terminal punctuation (and closing quotes) before a space, a CJK full stop,
or a blank line."""
_CLAUSE_END = re.compile(r"[,;:\u2014]+(?=\s)|[\uff0c\uff1b\uff1a\u3001]")
_SPACE = re.compile(r"\s+")
_WORD = re.compile(r"\w")
_LINE_BREAK = re.compile(r"\r\n|\r|\n")


def _last_end(pattern: re.Pattern[str], text: str, start: int, stop: int) -> int:
    """The end of the last match of ``pattern`` in ``text[start:stop]`` (``start`` if none)."""
    end = start
    for match in pattern.finditer(text, start, stop):
        end = match.end()
    return end


def _cut(text: str, start: int, limit: int) -> int:
    """Where the chunk from ``start`` ends: after the last sentence that fits, else a clause, else a
    word, else (one run of letters) at ``limit`` characters, never inside a combining sequence. A run
    without white space longer than :data:`MAX_RUN` is a chunk of its own, cut every MAX_RUN characters."""
    run = _LONG_RUN.search(text, start, start + limit + MAX_RUN + 1)
    if run is not None and run.start() >= start + limit:
        run = None  # it starts after this chunk
    if run is not None and run.start() > start:
        return run.start()  # the chunk ends before the run
    stop = start + (MAX_RUN if run is not None else limit)
    if stop >= len(text):
        return len(text)
    patterns = () if run is not None else (_SENTENCE_END, _CLAUSE_END, _SPACE)
    for pattern in patterns:
        end = _last_end(pattern, text, start, stop)
        if end > start:
            return end
    while stop > start + 1 and (unicodedata.combining(text[stop]) or "\udc00" <= text[stop] <= "\udfff"):
        stop -= 1
    return stop


def sentence_chunks(markup: Markup, limit: int = CHUNK_CHARS) -> Iterator[Markup]:
    """``markup`` as consecutive chunks of whole sentences, each at most ``limit`` characters (see the
    module docstring); text with nothing to say is one chunk, so that speaking it says so."""
    text, tags = markup.text, markup.tags
    starts: list[int] = []
    ends: list[int] = []
    at = 0
    while True:
        space = _SPACE.match(text, at)
        at = space.end() if space else at
        if at >= len(text):
            break
        end = _cut(text, at, limit)
        if starts and not _WORD.search(text, at, end):  # no word in it: said with the sentence before
            ends[-1] = end
        else:
            starts.append(at)
            ends.append(end)
        at = end
    if len(starts) <= 1:
        yield markup
        return
    t = 0
    for k, (start, end) in enumerate(zip(starts, ends)):
        following = starts[k + 1] if k + 1 < len(starts) else None
        mine = []
        while t < len(tags) and (following is None or tags[t].offset < following):
            mine.append(replace(tags[t], offset=min(max(tags[t].offset - start, 0), end - start)))
            t += 1
        places = markup.places[start:end] if markup.places else tuple(markup.place(i) for i in range(start, end))
        yield Markup(text[start:end], tuple(mine), markup.name, places)


def parse_pieces(source: str, *, name: str = "<text>", **options) -> Iterator[Markup]:
    """:func:`~.markup.parse_markup` of ``source`` of any length, in pieces of at most
    :data:`~.markup.MAX_TEXT_CHARS` characters cut between sentences and outside parentheses (one
    piece, the source itself, when it is that short); ``options`` go to ``parse_markup``. Lines and
    columns (of errors, tags and characters) are those of the whole source."""
    start, line, column = 0, 1, 1
    while True:  # once at least: an empty source is one empty piece
        stop = _safe_cut(source, start, MAX_TEXT_CHARS)
        piece = source[start:stop]
        try:
            markup = parse_markup(piece, name=name, **options)
        except MarkupError as exc:
            if start:
                exc.column = exc.column + column - 1 if exc.line == 1 else exc.column
                exc.line += line - 1
            raise
        yield markup if not start else _moved(markup, line, column)
        breaks = list(_LINE_BREAK.finditer(piece))
        line += len(breaks)
        column = len(piece) - breaks[-1].end() + 1 if breaks else column + len(piece)
        start = stop
        if start >= len(source):
            return


def _moved(markup: Markup, line: int, column: int) -> Markup:
    """A piece's markup placed where the piece starts in the source (``line``, ``column``)."""
    def place(at: tuple[int, int]) -> tuple[int, int]:
        return (at[0] + line - 1, at[1] + column - 1) if at[0] == 1 else (at[0] + line - 1, at[1])

    tags = tuple(replace(tag, line=place((tag.line, tag.column))[0], column=place((tag.line, tag.column))[1])
                 for tag in markup.tags)
    return Markup(markup.text, tags, markup.name, tuple(place(p) for p in markup.places), markup.malformed)


def _safe_cut(source: str, start: int, limit: int) -> int:
    """The end of a piece from ``start``: a sentence's end at most ``limit`` characters on, where no
    parenthesis is open (a tag runs to its ``)``), else a space outside parentheses, else ``limit``."""
    stop = start + limit
    if stop >= len(source):
        return len(source)
    for pattern in (_SENTENCE_END, _SPACE):
        best = start
        for match in pattern.finditer(source, start, stop):
            end = match.end()
            opening, closing = source.rfind("(", start, end), source.rfind(")", start, end)
            if opening <= closing and source[end:end + 1] != "(":
                best = end
        if best > start:
            return best
    return stop
