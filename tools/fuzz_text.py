"""Texts for the text fuzz target: any script, control characters, long lines, tags whole and broken, RTL, emoji.

Why generated rather than only mutated: the text path (``parse_markup`` -> ``encode_text``) is the one
every user takes, and what users type is not a damaged copy of a seed: it is text in one of a hundred
scripts, pasted with invisible marks, emoji and stray parentheses, sometimes a whole book on one line.
Each recipe is ``(rng) -> str``, deterministic for a given ``random.Random`` state, so a case is
reproducible from (target, seed, index). The seed sentences and tags are small text files written for
this under ``tools/fuzz_seeds/``.
"""
from __future__ import annotations

import random
import sys
from pathlib import Path
from typing import Callable

SEEDS = Path(__file__).resolve().parent / "fuzz_seeds"

SCRIPTS: dict[str, tuple[tuple[int, int], ...]] = {
    "latin": ((0x41, 0x5A), (0x61, 0x7A)), "latin-ext": ((0xC0, 0x24F), (0x1E00, 0x1EFF)),
    "ipa": ((0x250, 0x2AF), (0x2B0, 0x2FF)), "greek": ((0x370, 0x3FF), (0x1F00, 0x1FFF)),
    "cyrillic": ((0x400, 0x4FF), (0x500, 0x52F)), "armenian": ((0x531, 0x58A),), "hebrew": ((0x591, 0x5F4),),
    "arabic": ((0x600, 0x6FF), (0x750, 0x77F), (0xFB50, 0xFDFF), (0xFE70, 0xFEFC)), "syriac": ((0x700, 0x74F),),
    "thaana": ((0x780, 0x7B1),), "nko": ((0x7C0, 0x7FA),), "devanagari": ((0x900, 0x97F),),
    "bengali": ((0x980, 0x9FE),), "gurmukhi": ((0xA00, 0xA76),), "gujarati": ((0xA81, 0xAFF),),
    "oriya": ((0xB01, 0xB77),), "tamil": ((0xB82, 0xBFA),), "telugu": ((0xC00, 0xC7F),),
    "kannada": ((0xC80, 0xCF2),), "malayalam": ((0xD00, 0xD7F),), "sinhala": ((0xD81, 0xDF4),),
    "thai": ((0xE01, 0xE5B),), "lao": ((0xE81, 0xEDF),), "tibetan": ((0xF00, 0xFDA),),
    "myanmar": ((0x1000, 0x109F),), "georgian": ((0x10A0, 0x10FF),), "hangul-jamo": ((0x1100, 0x11FF),),
    "ethiopic": ((0x1200, 0x139F),), "cherokee": ((0x13A0, 0x13FD),), "canadian": ((0x1400, 0x167F),),
    "ogham": ((0x1680, 0x169C),), "runic": ((0x16A0, 0x16F8),), "khmer": ((0x1780, 0x17F9),),
    "mongolian": ((0x1800, 0x18AA),), "hiragana": ((0x3041, 0x309F),), "katakana": ((0x30A0, 0x30FF),),
    "bopomofo": ((0x3105, 0x312F),), "cjk": ((0x4E00, 0x9FFF),), "cjk-ext-b": ((0x20000, 0x2A6DF),),
    "yi": ((0xA000, 0xA48C),), "hangul": ((0xAC00, 0xD7A3),), "fullwidth": ((0xFF01, 0xFF5E),),
    "combining": ((0x300, 0x36F), (0x1AB0, 0x1AFF), (0x20D0, 0x20F0)), "math": ((0x2200, 0x22FF), (0x1D400, 0x1D7FF)),
    "arrows-box": ((0x2190, 0x21FF), (0x2500, 0x259F)), "braille": ((0x2800, 0x28FF),),
    "emoji": ((0x1F300, 0x1F5FF), (0x1F600, 0x1F64F), (0x1F680, 0x1F6FF), (0x1F900, 0x1F9FF)),
    "gothic": ((0x10330, 0x1034A),), "deseret": ((0x10400, 0x1044F),), "cuneiform": ((0x12000, 0x12399),),
    "music": ((0x1D100, 0x1D1EA),), "tags": ((0xE0001, 0xE007F),), "private": ((0xE000, 0xF8FF),),
    "digits": ((0x30, 0x39), (0x660, 0x669), (0x966, 0x96F), (0xFF10, 0xFF19)),
}
"""Unicode ranges by script or kind: every script a user may paste, and the odd corners of the code space."""

CONTROLS = ("\x00", "\x01", "\x07", "\x08", "\t", "\n", "\x0b", "\x0c", "\r", "\x1b", "\x1b[31m", "\x1b[0m",
            "\x7f", "\x85", "\x9b", "\xa0", "\xad", "\u200b", "\u200c", "\u200d", "\u2028", "\u2029", "\u2060",
            "\ufeff", "\ufff9", "\ufffc", "\ufffd", "\ufffe", "\uffff", "\U0010ffff", "\ud800", "\udfff",
            "\u180e", "\u115f", "\u3000", "\U000e0001")
"""Control and invisible characters, noncharacters and lone surrogates (they reach us from pasted text)."""
BIDI = ("\u200e", "\u200f", "\u061c", "\u202a", "\u202b", "\u202c", "\u202d", "\u202e", "\u2066", "\u2067",
        "\u2068", "\u2069")
"""Right-to-left and other direction marks, embeddings, overrides and isolates."""
EMOJI = ("😀", "👍🏽", "👨‍👩‍👧‍👦", "🏳️‍🌈", "🇫🇷", "🇺🇳", "1️⃣", "#️⃣", "❤️", "🧑🏿‍🚀", "🫠", "🏴󠁧󠁢󠁳󠁣󠁴󠁿",
         "☃︎", "⌚", "👩🏻‍❤️‍💋‍👨🏼", "🦱", "\U0001F3FB")
"""Emoji: ZWJ sequences, skin tones, flags, keycaps, tag sequences, variation selectors, a lone modifier."""
NUMBERS = ("0", "7", "1,234.56", "$1,000,000", "€5", "£3.50", "¥100", "3/4", "½", "1e308", "1e-308", "NaN", "inf",
           "-0", "007", "1" * 40, "9" * 400, "3.14159265358979323846", "10:30", "2021-03-04", "1st", "22nd",
           "XIV", "IV", "0x1F", "192.168.0.1", "+1-555-0100", "50%", "°C", "#1", "12:00:00.000")
EXPRESSIONS = ("joy", "sadness", "anger", "fear", "disgust", "surprise", "JOY", "Joy", "neutral", "happiness",
               "joyful", "j", "ジョイ", "joy_", "_joy", "joy1", "x" * 300)
TAG_NUMBERS = ("0", "1", "40", "63", "64", "-1", "+12", "0.5", ".5", "5.", "1e308", "1e-400", "nan", "inf", "-inf",
               "99999999999999999999", "0" * 200, "1_0", "٤٠", "４０", "0x10", "", " ", "1.2.3", "--1", "1e")


def _load(name: str) -> list[tuple[str, str]]:
    """``(lang, text)`` lines of a seed file (tags.txt lines have no language: ``auto``)."""
    out = []
    for line in (SEEDS / name).read_text(encoding="utf-8").splitlines():
        if not line or line.startswith("#"):
            continue
        lang, tab, text = line.partition("\t")
        out.append((lang, text) if tab else ("auto", line))
    return out


SENTENCES = _load("sentences.txt")
TAG_LINES = [text for _, text in _load("tags.txt")]


def _char(rng: random.Random, ranges: tuple[tuple[int, int], ...]) -> str:
    low, high = rng.choice(ranges)
    return chr(rng.randint(low, high))


def script_words(rng: random.Random, script: str | None = None, words: int | None = None) -> str:
    """Random 'words' of one script (or of several), with spaces and some punctuation."""
    ranges = SCRIPTS[script or rng.choice(sorted(SCRIPTS))]
    out = []
    for _ in range(words if words is not None else rng.choice((1, 2, 5, 12, 40))):
        out.append("".join(_char(rng, ranges) for _ in range(rng.choice((1, 2, 3, 5, 8, 20)))))
        if rng.random() < 0.15:
            out[-1] += rng.choice((".", ",", "!", "?", ";", ":", "…", "。", "،", "؟", "।", "–"))
    return " ".join(out)


def any_code_points(rng: random.Random) -> str:
    """Code points from the whole space: unassigned, surrogates, noncharacters, private use, astral."""
    n = rng.choice((1, 3, 10, 50, 300))
    picks = []
    for _ in range(n):
        r = rng.random()
        if r < 0.5:
            picks.append(chr(rng.randrange(0x20, 0x3000)))
        elif r < 0.8:
            picks.append(chr(rng.randrange(0x110000)))
        else:
            picks.append(rng.choice(CONTROLS + BIDI))
    return "".join(picks)


def sentence(rng: random.Random) -> str:
    """A seed sentence in some language, sometimes with its words shuffled, doubled or cut."""
    text = rng.choice(SENTENCES)[1]
    words = text.split(" ")
    op = rng.randrange(5)
    if op == 1:
        rng.shuffle(words)
    elif op == 2 and words:
        i = rng.randrange(len(words))
        words.insert(i, words[i] * rng.choice((2, 5, 50)))
    elif op == 3 and words:
        words = words[:rng.randrange(len(words) + 1)]
    elif op == 4:
        cut = rng.randrange(len(text) + 1)
        return text[:cut]
    return " ".join(words)


def _number(rng: random.Random) -> str:
    return rng.choice(TAG_NUMBERS) if rng.random() < 0.6 else repr(rng.uniform(-100, 100))[:rng.randint(1, 8)]


def tag(rng: random.Random) -> str:
    """One tag, mostly well formed, else damaged in one way (missing comma, unknown name, out of range...)."""
    name = rng.choice(EXPRESSIONS[:6]) if rng.random() < 0.7 else rng.choice(EXPRESSIONS)
    fields = [name, str(rng.randint(0, 63)) if rng.random() < 0.7 else _number(rng),
              f"{rng.uniform(0, 3):.2f}" if rng.random() < 0.7 else _number(rng)]
    seps = [", "] * 2
    op = rng.randrange(8) if rng.random() < 0.5 else -1
    if op == 0:
        seps[rng.randrange(2)] = " "
    elif op == 1:
        fields.pop(rng.randrange(1, 3))
        seps.pop()
    elif op == 2:
        fields.append(_number(rng))
        seps.append(",")
    body = fields[0] + "".join(s + f for s, f in zip(seps, fields[1:]))
    opening, closing = "(", ")"
    if op == 3:
        closing = ""
    elif op == 4:
        opening = ""
    elif op == 5:
        opening, closing = "\\(", "\\)"
    elif op == 6:
        opening, closing = "((", "))"
    elif op == 7:
        body = body.replace(", ", ",") .replace(",", rng.choice(("，", "、", ";", ", ,")), 1)
    return opening + body + closing


def tagged(rng: random.Random) -> str:
    """Text with tags among its words: several, adjacent, nested, inside words, at the end, unclosed."""
    parts = []
    for _ in range(rng.choice((1, 2, 4, 10, 50))):
        r = rng.random()
        if r < 0.4:
            parts.append(tag(rng))
        elif r < 0.5:
            inner = tag(rng)
            outer = tag(rng)
            cut = rng.randrange(1, len(outer))
            parts.append(outer[:cut] + inner + outer[cut:])
        elif r < 0.6:
            parts.append(rng.choice(TAG_LINES))
        elif r < 0.7:
            parts.append(rng.choice(("(", ")", "((", "))", "()", "(,)", "(a,", "\\", "\\(", "(see below)")))
        else:
            parts.append(sentence(rng))
    sep = rng.choice((" ", "", "\n", " \r\n", "\t"))
    return sep.join(parts)


def decorated(rng: random.Random) -> str:
    """A sentence with control characters, direction marks, emoji or numbers dropped between its characters."""
    text = list(sentence(rng))
    pool = rng.choice((CONTROLS, BIDI, EMOJI, NUMBERS, CONTROLS + BIDI + EMOJI))
    for _ in range(rng.choice((1, 3, 10, 40))):
        text.insert(rng.randint(0, len(text)), rng.choice(pool) + (" " if pool is NUMBERS else ""))
    return "".join(text)


def mixed(rng: random.Random) -> str:
    """Several recipes joined: scripts switching mid-sentence, as pasted text does."""
    pieces = [rng.choice(SMALL)(rng) for _ in range(rng.choice((2, 3, 5)))]
    return rng.choice((" ", "", "\n", "\u200b")).join(pieces)


def long_line(rng: random.Random) -> str:
    """A long line: 10 kB to 1 MB, one word repeated, one huge word, digits, tags, or a sentence over and over."""
    size = rng.choice((10_000, 60_000, 150_000, 199_999, 200_001, 1 << 20))
    op = rng.randrange(7)
    if op == 0:
        unit = sentence(rng) + " "
    elif op == 1:
        unit = _char(rng, SCRIPTS[rng.choice(("latin", "cjk", "arabic", "devanagari", "hangul"))])
    elif op == 2:
        unit = rng.choice(("9", "1,000 ", "3.14 ", ".", "!", "-", "a.", "… "))
    elif op == 3:
        unit = tag(rng) + " "
    elif op == 4:
        unit = script_words(rng, words=20) + " "
    elif op == 5:
        unit = rng.choice(EMOJI + BIDI + CONTROLS)
    else:
        unit = "(" if rng.random() < 0.5 else ")"
    text = unit * (size // max(len(unit), 1) + 1)
    return text[:size] if rng.random() < 0.8 else "\n" * rng.randint(0, 3) + text[:size] + "\n"


def many_lines(rng: random.Random) -> str:
    """Many short lines (or empty ones): line and column bookkeeping, CR/LF mixtures."""
    n = rng.choice((100, 10_000, 50_000))
    line = rng.choice(("", " ", "a", "(joy, 1, 1)", "\u200f", "你好", sentence(rng)))
    return rng.choice(("\n", "\r\n", "\r", "\u2028", "\x85")).join([line] * n)


def blank(rng: random.Random) -> str:
    """Nothing to say: empty, whitespace, only tags, only punctuation, only marks."""
    return rng.choice(("", " ", "\n\n", "\t \r\n", "(joy, 40, 0.5)", "(joy, 40, 0.5) (sadness, 1, 1)", "...",
                       "!?", "\u200b\u200e", "\ufeff", "\x00", "-- --", "()", "😀", "١٢٣", "123"))


SMALL: tuple[Callable[[random.Random], str], ...] = (script_words, any_code_points, sentence, sentence, tag, tagged,
                                                     decorated, blank)
RECIPES: tuple[tuple[Callable[[random.Random], str], float], ...] = (
    (sentence, 0.16), (script_words, 0.14), (tagged, 0.16), (decorated, 0.14), (mixed, 0.14),
    (any_code_points, 0.1), (blank, 0.04), (long_line, 0.08), (many_lines, 0.04),
)
"""Recipes and their shares: mostly text of a sentence's or a page's size; long lines now and then."""


def draw_text(rng: random.Random) -> tuple[str, str]:
    """One text and the recipe that made it."""
    recipes, weights = zip(*RECIPES)
    recipe = rng.choices(recipes, weights)[0]
    return recipe(rng), recipe.__name__


def text_bytes(text: str) -> bytes:
    """How a text case is kept (and saved as a reproducer): UTF-8, lone surrogates passed through."""
    return text.encode("utf-8", "surrogatepass")


def bytes_text(data: bytes) -> str:
    """The text of a case (a reproducer edited by hand may hold any bytes: those become U+FFFD)."""
    try:
        return data.decode("utf-8", "surrogatepass")
    except UnicodeDecodeError:
        return data.decode("utf-8", "replace")


if __name__ == "__main__":  # a look at what the recipes make: python tools/fuzz_text.py [N]
    r = random.Random(0)
    for _ in range(int(sys.argv[1]) if len(sys.argv) > 1 else 20):
        t, how = draw_text(r)
        print(f"{how:>16} {len(t):>8} {t[:100]!r}")
