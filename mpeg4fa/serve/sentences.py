"""Tagged text cut into sentences, so the server can speak and send the first while the next is made.

The whole text is parsed once (:func:`~mpeg4fa.speech.markup.parse_markup`), so a malformed tag
anywhere is refused before anything is spoken, with its line and column in the text as sent. The
plain text is cut after ``.``, ``!``, ``?``, ``;`` (and the Chinese ``。！？；``) followed by
whitespace or the end, and each piece is written back as tagged text with its own tags. Tags
hold across sentences, but each sentence is encoded on its own: so every expression still
raised when a sentence begins is set again at its start (reached at once, ``seconds`` 0), and
the face keeps its expression from one sentence into the next. A transition still under way at
a sentence's end jumps to its target there: the one place the cut shows.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from mpeg4fa.speech.markup import Markup, Tag, parse_markup

_END = re.compile(r"[.!?;。！？；]+[\"'”’)\]]*(?=\s|$)|[。！？；]+")
_ESCAPE = str.maketrans({"(": r"\(", ")": r"\)", "\\": "\\\\"})
MAX_SENTENCE_CHARS = 400
"""A run of text with no sentence end is cut at its last space before this many characters."""


@dataclass(frozen=True)
class Sentence:
    index: int
    text: str  # tagged text of this sentence alone, ready for encode_text
    plain: str  # what is spoken
    start: int  # offset of ``plain`` in the whole text's plain text


def split_sentences(source: str, *, name: str = "<text>") -> list[Sentence]:
    """The sentences of tagged ``source`` as tagged texts (raises :class:`MarkupError` for a bad tag)."""
    markup = parse_markup(source, name=name)
    spans = _spans(markup.text)
    return [_tagged(i, markup, a, b, i == len(spans) - 1) for i, (a, b) in enumerate(spans)]


def _spans(text: str) -> list[tuple[int, int]]:
    cuts, start = [], 0
    for match in _END.finditer(text):
        cuts.extend(_long(text, start, match.end()))
        start = match.end()
    cuts.extend(_long(text, start, len(text)))
    spans = []
    for a, b in cuts:
        while a < b and text[a].isspace():
            a += 1
        while b > a and text[b - 1].isspace():
            b -= 1
        if a < b:
            spans.append((a, b))
    return spans


def _long(text: str, a: int, b: int) -> list[tuple[int, int]]:
    """``text[a:b]`` in pieces of at most about MAX_SENTENCE_CHARS, cut at spaces where there are some."""
    pieces = []
    while b - a > MAX_SENTENCE_CHARS:
        cut = text.rfind(" ", a + 1, a + MAX_SENTENCE_CHARS)
        cut = cut if cut > a else a + MAX_SENTENCE_CHARS
        pieces.append((a, cut))
        a = cut
    pieces.append((a, b))
    return pieces


def _tag(tag: Tag, seconds: float | None = None) -> str:
    return f"({tag.expression}, {tag.intensity}, {tag.seconds if seconds is None else seconds:g})"


def _tagged(index: int, markup: Markup, a: int, b: int, last: bool) -> Sentence:
    held: dict[str, Tag] = {}
    for tag in markup.tags:  # what earlier sentences left raised
        if tag.offset < a:
            held[tag.expression] = tag
    parts = [_tag(t, 0.0) + " " for t in held.values() if t.intensity > 0]
    at = a
    for tag in markup.tags:  # a tag's offset is the first character spoken after it
        if a <= tag.offset < b or (last and tag.offset == b):
            parts.append(markup.text[at:tag.offset].translate(_ESCAPE))
            parts.append(_tag(tag))
            at = tag.offset
    parts.append(markup.text[at:b].translate(_ESCAPE))
    return Sentence(index, "".join(parts), markup.text[a:b], a)
