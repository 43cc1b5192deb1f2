"""Mandarin text to syllables and Chinese visemes: hanzi -> pinyin (pypinyin) -> initial,
glide, main vowel, ending -> the 15 visemes of ``spec/chinese_visemes.csv``.

pypinyin reads whole phrases, so polyphones follow their words (重庆 chong2, 银行 hang2)
and 一/不 take their sandhi tones; its strict finals are the standard ones (``uei``,
``iou``, ``uen``; 鱼 is initial ``""`` + final ``v``). Tones are kept on every syllable.

A syllable gives one viseme per articulation, in order:

* the initial (b p m -> bpm, zh ch sh -> zhchsh, ...); the whole syllables
  zi ci si, zhi chi shi, ri are one viseme (the apical i keeps the initial's shape);
* the glide of a final (i-, u-, v-: the i of ``iao``, the u of ``uan``, the ü of ``ve``);
* the main vowel: the viseme the table lists for the whole final (``iao`` -> a);
* the ending: -i (``ai ei uai uei``), -o (``ao iao``), -u (``ou iou``), -n, -ng;
  ``er`` is r alone, an erhua ending ``r`` adds r.
"""
from __future__ import annotations

from dataclasses import dataclass

from mpeg4fa.spec import CHINESE_VISEME_BY_PINYIN, MANDARIN_PART_WEIGHT
from mpeg4fa.speech.errors import MarkupError
from mpeg4fa.speech.script import HAN, HAN_RUN

_WHOLE = {"z", "c", "s", "zh", "ch", "sh", "r"}
_ENDINGS = {"ai": "-i", "ei": "-i", "uai": "-i", "uei": "-i", "ao": "-o", "iao": "-o", "ou": "-u", "iou": "-u"}
_NO_GLIDE = {"in", "ing", "vn"}


@dataclass(frozen=True)
class Syllable:
    """One hanzi as spoken: where it stands in the text, its pinyin and its visemes."""

    text: str
    position: int        # character offset in the text
    initial: str         # "" for zero-initial syllables
    final: str           # strict pinyin final, without tone ("ao", "iou", "v", ...)
    tone: int            # 1-4, 5 = neutral
    visemes: tuple[str, ...]

    @property
    def pinyin(self) -> str:
        """Tone-numbered pinyin as espeak's pinyin voice reads it (ü written v)."""
        return _spelled(self.initial, self.final) + str(self.tone)


def has_glide(final: str) -> bool:
    """Whether a strict final opens with a glide (the i of ``iao``, the u of ``uan``, the ü of ``ve``)."""
    return len(final) > 1 and final[0] in "iuv" and final not in _NO_GLIDE


FINAL_WEIGHT = MANDARIN_PART_WEIGHT
"""Relative lengths of a final's parts when the engine does not time them (``spec/mandarin_weights.csv``):
the main vowel carries the syllable, a glide passes quickly, an ending is in between."""


def final_roles(final: str, count: int) -> list[str]:
    """The role (glide, main, ending) of each of the ``count`` visemes a final shows, in order."""
    glide = count > 1 and has_glide(final)
    return ["glide" if glide and k == 0 else ("main" if k == int(glide) else "ending") for k in range(count)]


def syllable_visemes(initial: str, final: str) -> tuple[str, ...]:
    """The visemes of one syllable, from its strict initial and final (see the module docstring)."""
    table = CHINESE_VISEME_BY_PINYIN
    erhua = final.endswith("r") and final != "er"
    if erhua:
        final = final[:-1]
    out: list[str] = []
    if initial in _WHOLE and final == "i":
        out.append(table[initial + "i"])
    else:
        if initial:
            out.append(table[initial])
        if final == "er":
            out.append(table["er"])
        elif final in table:
            if has_glide(final):
                out.append(table[final[0] + "-"])
            out.append(table[final])
            if final.endswith("ng"):
                out.append(table["-ng"])
            elif final.endswith("n"):
                out.append(table["-n"])
            elif final in _ENDINGS:
                out.append(table[_ENDINGS[final]])
        else:
            raise KeyError(f"pinyin final {final!r} is not in spec/chinese_visemes.csv")
    if erhua:
        out.append(table["-r"])
    return tuple(out)


def _spelled(initial: str, final: str) -> str:
    """Strict initial + final back to written pinyin (iou -> iu after an initial, y/w spellings)."""
    if initial:
        short = {"iou": "iu", "uei": "ui", "uen": "un"}.get(final, final)
        if initial in ("j", "q", "x") and short.startswith("v"):
            short = "u" + short[1:]
        return initial + short
    if final.startswith("i"):
        return "y" + (final[1:] if has_glide(final) else final)
    if final.startswith("u"):
        return "w" + (final[1:] if len(final) > 1 else final)
    if final.startswith("v"):
        return "yu" + final[1:]
    return final


def syllables(text: str) -> list[Syllable]:
    """Every hanzi of ``text`` as a :class:`Syllable` (other characters are skipped)."""
    from pypinyin import Style, lazy_pinyin

    positions = [m.start() for m in HAN.finditer(text)]
    if not positions:
        return []
    chars = "".join(text[p] for p in positions)
    # phrase-aware readings need the characters in their words: read runs of adjacent hanzi together
    initials, finals = [], []
    for run in HAN_RUN.finditer(text):
        initials += lazy_pinyin(run.group(), style=Style.INITIALS, strict=True)
        finals += lazy_pinyin(run.group(), style=Style.FINALS_TONE3, strict=True, neutral_tone_with_five=True)
    out = []
    for pos, ch, ini, fin in zip(positions, chars, initials, finals):
        tone = int(fin[-1]) if fin and fin[-1].isdigit() else 5
        final = fin.rstrip("012345")
        try:
            visemes = syllable_visemes(ini, final)
        except KeyError as exc:
            line = text.count("\n", 0, pos) + 1
            column = pos - (text.rfind("\n", 0, pos) + 1) + 1
            raise MarkupError(f"{ch!r} reads as {ini}{fin}, which has no viseme mapping ({exc.args[0]})",
                              line, column) from None
        out.append(Syllable(ch, pos, ini, final, tone, visemes))
    return out
