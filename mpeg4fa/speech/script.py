"""Which writing system each character belongs to, and refusing text no voice here can speak.

Why: the voices speak English (Latin letters) and Mandarin (hanzi read as pinyin). Text
in any other script (Arabic, Hebrew, Hangul, kana, Thai, Devanagari, Cyrillic, Greek...)
would be sent to the English voice, come back as silence or spelt-out noise, and give a
stream whose mouth never moves, with no error. So such text is refused, naming the script
and the characters, until a voice for it is added.

The script is read from the character's Unicode name (``unicodedata``): after NFKC
folding (full-width Latin is Latin, half-width katakana is katakana), a letter, mark or
digit is of the script its name starts with (``ARABIC LETTER ALEF`` -> Arabic,
``CJK UNIFIED IDEOGRAPH-4E2D`` -> Han). Punctuation, symbols, spaces, European digits,
modifier letters and combining accents belong to no script and are always accepted.
This module is also where :mod:`.utterance` learns which characters are Chinese.
"""
from __future__ import annotations

import re
import unicodedata
from collections.abc import Callable
from functools import lru_cache

from mpeg4fa.speech.errors import MarkupError

HAN = re.compile(r"[\u3400-\u4dbf\u4e00-\u9fff\uf900-\ufaff]")
HAN_RUN = re.compile(HAN.pattern + "+")
"""Hanzi the pinyin reader knows (CJK unified ideographs, extension A, compatibility ideographs)."""
CHINESE = re.compile(r"[\u3400-\u4dbf\u4e00-\u9fff\uf900-\ufaff\u3000-\u303f\uff00-\uffef]")
"""What a Chinese run is made of: hanzi, CJK punctuation and full-width forms."""
SPOKEN = {"Latin": "English", "Han": "Mandarin"}
"""Script -> the language it is spoken in."""
_NO_SCRIPT = {"COMBINING", "MODIFIER", "DIGIT", "IDEOGRAPHIC"}
"""Name prefixes of letters and digits shared by all scripts (accents, ʼ, 0-9, 々 〆 〇)."""
_NAMED_BY_TWO = {"OLD", "CANADIAN", "NEW", "TAI", "PAU", "MASARAM", "NYIAKENG", "HANIFI", "ZANABAZAR"}
_QUOTE_MAX = 24
_HINT = "English and Mandarin are spoken; other languages come later"


@lru_cache(maxsize=4096)
def script_of(char: str) -> str | None:
    """The script of one character (``"Latin"``, ``"Han"``, ``"Arabic"``...), None for a script-less one."""
    folded = unicodedata.normalize("NFKC", char)
    scripts = {s for s in map(_script_of_folded, folded) if s is not None}
    if not scripts:
        return None
    return sorted(scripts)[0] if len(scripts) > 1 else scripts.pop()


def _script_of_folded(char: str) -> str | None:
    if unicodedata.category(char)[0] not in "LMN" or unicodedata.category(char) in ("Nl", "No"):
        return None
    name = unicodedata.name(char, "")
    if not name:
        return None
    if name.startswith("CJK "):
        return "Han"
    words = name.split()
    if words[0] in _NO_SCRIPT:
        return None
    first = words[0] if words[0] not in _NAMED_BY_TWO or len(words) < 2 else f"{words[0]} {words[1]}"
    return first.title()


def speakable(char: str, lang: str) -> bool:
    """Whether a voice for ``lang`` (``en``, ``zh`` or ``auto``) speaks ``char``; script-less ones always."""
    script = script_of(char)
    if script is None or script == "Latin":
        return True
    return script == "Han" and lang != "en" and HAN.match(char) is not None


def line_column(text: str, index: int) -> tuple[int, int]:
    """1-based line and column of ``text[index]`` (lines end at ``\\n``)."""
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def check_speakable(text: str, lang: str = "auto", name: str = "<text>",
                    place: Callable[[int], tuple[int, int]] | None = None) -> None:
    """Raise :class:`MarkupError` at the first character no voice for ``lang`` speaks, quoting its run.

    With ``lang="en"`` hanzi are refused as well (they would need the Mandarin voice).
    ``place`` gives the source (line, column) of ``text[i]`` (:meth:`.Markup.place`: where the user wrote
    it, tags included); without it they count in ``text`` as given.
    """
    for index, char in enumerate(text):
        if char < "\x80" or speakable(char, lang):
            continue
        script = script_of(char)
        line, column = place(index) if place is not None else line_column(text, index)
        if script == "Han" and HAN.match(char):
            raise MarkupError(f"{char!r} is Chinese but --lang is en", line, column,
                              hint="use --lang zh or auto", source=name)
        run = _run_of(text, index, script)
        raise MarkupError(f"cannot speak {script} text: {_quote(run)}", line, column, hint=_HINT, source=name)


def _run_of(text: str, start: int, script: str | None) -> str:
    """The characters from ``start`` on in ``script`` (with the spaces and accents between them)."""
    end = start
    for index in range(start, min(len(text), start + 4 * _QUOTE_MAX)):
        found = script_of(text[index])
        if found == script:
            end = index + 1
        elif found is not None or text[index] == "\n":
            break
    return text[start:end]


def _quote(run: str) -> str:
    return repr(run if len(run) <= _QUOTE_MAX else run[:_QUOTE_MAX] + "...")
