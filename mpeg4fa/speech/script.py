"""Which writing system each character belongs to, and refusing text no voice here can speak.

Why: text sent to a voice that cannot read its script comes back as silence or spelt-out
noise ("Chinese letter"), and gives a stream whose mouth never moves, with no error. So text
no voice here reads is refused, naming the script and the characters. Which voices read what:

* engines with IPA phoneme events (espeak-ng), ``--lang auto``: Latin is English, Han alone
  Mandarin (pinyin), Cyrillic Russian, Arabic Arabic, Devanagari Hindi, kana (with the Han
  next to it) Japanese (:data:`AUTO_LANGUAGES`, :func:`runs`); other scripts are refused;
* ``--lang CODE`` (any espeak-ng language): the whole text goes to that voice, except that
  hanzi are read only by the Chinese voices and kana only by the Japanese one (espeak-ng's
  Japanese voice reads no kanji: they are refused, with where they are);
* engines with word boundaries only (pyttsx3, the silent estimator): English and Mandarin.

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
"""Script -> the language it is spoken in (engines without IPA phoneme events)."""
AUTO_LANGUAGES = {"Latin": "en", "Han": "zh", "Cyrillic": "ru", "Arabic": "ar", "Devanagari": "hi",
                  "Hiragana": "ja", "Katakana": "ja", "Katakana-Hiragana": "ja"}
"""Script -> the language ``--lang auto`` speaks it in (engines with IPA phoneme events)."""
KANA = frozenset({"Hiragana", "Katakana", "Katakana-Hiragana"})
HAN_READERS = ("zh", "cmn", "yue", "hak")
"""Language codes (and their ``-`` variants) whose voices read hanzi."""
_NO_SCRIPT = {"COMBINING", "MODIFIER", "DIGIT", "IDEOGRAPHIC"}
"""Name prefixes of letters and digits shared by all scripts (accents, ʼ, 0-9, 々 〆 〇)."""
_NAMED_BY_TWO = {"OLD", "CANADIAN", "NEW", "TAI", "PAU", "MASARAM", "NYIAKENG", "HANIFI", "ZANABAZAR"}
_QUOTE_MAX = 24
_HINT = "English and Mandarin are spoken; other languages come later"
_HINT_IPA = ("--lang auto speaks Latin (English), Han (Mandarin), Cyrillic (ru), Arabic (ar), Devanagari (hi) "
             "and kana (ja); for another language give --lang CODE (mpeg4fa voices lists them)")


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


def _family(lang: str, codes: tuple[str, ...]) -> bool:
    lang = lang.lower()
    return any(lang == c or lang.startswith(c + "-") for c in codes)


def speakable(char: str, lang: str, languages: bool = False) -> bool:
    """Whether a voice for ``lang`` speaks ``char``; script-less ones always.

    ``languages``: the engine speaks any espeak-ng language (IPA phoneme events); without it only
    ``en``, ``zh`` and ``auto`` over Latin and Han are spoken.
    """
    script = script_of(char)
    if script is None or script == "Latin":
        return True
    if script == "Han" and HAN.match(char) is None:
        return False
    if lang in ("en", "zh") or not languages:
        return script == "Han" and lang != "en"
    if lang == "auto":
        return script in AUTO_LANGUAGES
    if script == "Han":
        return _family(lang, HAN_READERS) or _family(lang, ("ja",))  # ja: refused by check_speakable, with a reason
    if script in KANA:
        return _family(lang, ("ja",))
    return True  # the voice's own script, or one espeak-ng switches language for


def _kind(char: str) -> str:
    """What ``--lang auto`` makes of one character: a language, or ws / neutral / han / cjk to resolve."""
    script = script_of(char)
    if script in KANA:
        return "ja"
    if HAN.match(char):
        return "han"
    if CHINESE.match(char):
        return "cjk"
    if char.isspace():
        return "ws"
    if script is None:
        return "neutral"
    return AUTO_LANGUAGES.get(script, "en")


def runs(text: str, lang: str = "auto", languages: bool = False) -> list[tuple[str, int, int]]:
    """(language, start, end) runs of ``text``, each spoken by one voice; blank runs left out.

    ``en``/``zh``, or ``auto`` without ``languages``: hanzi and CJK punctuation are ``zh``, the
    rest ``en`` (spaces join the run before them). ``auto`` with ``languages``: by script
    (:data:`AUTO_LANGUAGES`); hanzi touching kana are Japanese, CJK punctuation goes with the
    run before it, as do punctuation and digits after a Cyrillic, Arabic, Devanagari or kana run.
    Any other ``lang``: the whole text in that language.
    """
    if lang not in ("auto", "en", "zh"):
        return [(lang, 0, len(text))] if text.strip() else []
    kinds = [_kind(ch) for ch in text]
    if lang != "auto" or not languages:
        kinds = ["zh" if k in ("han", "cjk", "ja") and CHINESE.match(ch) else ("ws" if k == "ws" else "en")
                 for k, ch in zip(kinds, text)]
    else:
        _resolve_han(kinds)
    resolved: list[str] = []
    for i, k in enumerate(kinds):
        previous = resolved[-1] if resolved else None
        if k == "ws":
            k = previous or "en"
        elif k == "cjk":
            k = "ja" if previous == "ja" else "zh"
        elif k == "neutral":
            if previous is None:
                following = next((n for n in kinds[i:] if n not in ("ws", "neutral")), "en")
                k = following if following not in ("zh", "han", "cjk") else "en"
            else:
                k = previous if previous not in ("en", "zh") else "en"
        resolved.append(k)
    out: list[tuple[str, int, int]] = []
    for i, k in enumerate(resolved):
        if out and out[-1][0] == k:
            out[-1] = (k, out[-1][1], i + 1)
        else:
            out.append((k, i, i + 1))
    return [r for r in out if text[r[1]:r[2]].strip()]


def _resolve_han(kinds: list[str]) -> None:
    """Each group of hanzi becomes ``ja`` when kana touch it on either side, else ``zh`` (in place)."""
    i = 0
    while i < len(kinds):
        if kinds[i] != "han":
            i += 1
            continue
        j = i
        while j < len(kinds) and kinds[j] == "han":
            j += 1
        japanese = (i > 0 and kinds[i - 1] == "ja") or (j < len(kinds) and kinds[j] == "ja")
        kinds[i:j] = ["ja" if japanese else "zh"] * (j - i)
        i = j


def line_column(text: str, index: int) -> tuple[int, int]:
    """1-based line and column of ``text[index]`` (lines end at ``\\n``)."""
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def check_speakable(text: str, lang: str = "auto", name: str = "<text>",
                    place: Callable[[int], tuple[int, int]] | None = None, *, languages: bool = False) -> None:
    """Raise :class:`MarkupError` at the first character no voice for ``lang`` speaks, quoting its run.

    With ``lang="en"`` hanzi are refused as well (they would need the Mandarin voice), and so are
    hanzi in Japanese text (espeak-ng's Japanese voice reads kana only). ``place`` gives the
    source (line, column) of ``text[i]`` (:meth:`.Markup.place`: where the user wrote it, tags
    included); without it they count in ``text`` as given. ``languages``: see :func:`speakable`.
    """
    def where(index: int) -> tuple[int, int]:
        return place(index) if place is not None else line_column(text, index)

    for index, char in enumerate(text):
        if char < "\x80" or speakable(char, lang, languages):
            continue
        script = script_of(char)
        line, column = where(index)
        if script == "Han" and HAN.match(char) and lang == "en":
            raise MarkupError(f"{char!r} is Chinese but --lang is en", line, column,
                              hint="use --lang zh or auto", source=name)
        if script == "Han" and HAN.match(char):
            raise MarkupError(f"{char!r} is Chinese, which the {lang} voice does not read", line, column,
                              hint="use --lang zh, yue or auto", source=name)
        if script in KANA and languages and lang not in ("auto", "en", "zh"):
            raise MarkupError(f"{char!r} is Japanese kana, which the {lang} voice does not read", line, column,
                              hint="use --lang ja or auto", source=name)
        run = _run_of(text, index, script)
        raise MarkupError(f"cannot speak {script} text: {_quote(run)}", line, column,
                          hint=_HINT_IPA if languages else _HINT, source=name)
    if not languages or lang in ("en", "zh"):
        return
    for kind, start, end in runs(text, lang, languages):
        if not _family(kind, ("ja",)):
            continue
        found = HAN.search(text, start, end)
        if found is not None:
            line, column = where(found.start())
            kanji = HAN_RUN.match(text, found.start()).group()
            raise MarkupError(f"espeak-ng's Japanese voice reads kana, not kanji: {_quote(kanji)}", line, column,
                              hint="write it in hiragana or katakana", source=name)


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
