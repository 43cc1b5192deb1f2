"""Letters to visemes with duration weights, for engines that report words but no phonemes.

pyttsx3 (like SAPI 5 in the seed design) says *when* each word starts, not what is
said inside it. The word's visemes then come from its spelling: English by the
longest matching grapheme of ``spec/english_graphemes.csv`` (``th`` before ``t``; a
grapheme may be bound to the word's start, end or middle), Mandarin from the
pinyin syllable (:mod:`.mandarin`). Each viseme carries a weight; a duration is
``weight * UNIT`` seconds at the reference rate, scaled by ``REFERENCE_RATE / rate``.
Weights follow the seed's rule: open vowels (a, o) and bilabials (b, p, m) last
longer, a medial u and the alveolars (d, t, n, l) shorter.

``UNIT`` and ``SYLLABLE_UNIT`` were measured on espeak-ng 1.52 at 175 words per
minute (voiced time / total weight of the README texts); they only set the pace,
the word boundaries the engine reports keep the visemes in sync.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

from mpeg4fa.spec import MANDARIN_DEFAULT_INITIAL_WEIGHT, MANDARIN_INITIAL_WEIGHT, VISEME_PROFILES
from mpeg4fa.spec._load import read_table
from mpeg4fa.speech.mandarin import FINAL_WEIGHT, Syllable, final_roles, syllable_visemes
from mpeg4fa.speech.wordsync import Unit

REFERENCE_RATE = 175     # words per minute the units were measured at
UNIT = 0.081             # seconds per unit of English weight at REFERENCE_RATE
SYLLABLE_UNIT = 0.135    # seconds per unit of Mandarin weight at REFERENCE_RATE
POSITIONS = ("any", "initial", "medial", "final")
# A Mandarin initial by its class, on the scale of mandarin.FINAL_WEIGHT (main vowel = 1): spec/mandarin_weights.csv.
_INITIAL_WEIGHT = MANDARIN_INITIAL_WEIGHT
_DEFAULT_INITIAL_WEIGHT = MANDARIN_DEFAULT_INITIAL_WEIGHT


@dataclass(frozen=True)
class Grapheme:
    """One spelled unit of a word and the visemes it shows, with its duration weight."""

    text: str
    visemes: tuple[str, ...]
    weight: float
    position: int  # character offset in the word


@lru_cache(maxsize=None)
def english_graphemes() -> dict[tuple[str, str], tuple[tuple[str, ...], float]]:
    """(grapheme, position) -> (visemes, weight), from ``spec/english_graphemes.csv``."""
    table: dict[tuple[str, str], tuple[tuple[str, ...], float]] = {}
    known = VISEME_PROFILES["mpeg4"]
    for row in read_table("english_graphemes.csv", "grapheme,position,visemes,weight,example"):
        key = (row["grapheme"], row["position"])
        visemes = tuple(row["visemes"].split())
        bad = [v for v in visemes if v not in known]
        if bad or row["position"] not in POSITIONS or key in table:
            raise ValueError(f"english_graphemes.csv: bad row {row}")
        table[key] = (visemes, float(row["weight"]))
    return table


@lru_cache(maxsize=None)
def _longest() -> int:
    return max(len(g) for g, _ in english_graphemes())


def english_word(word: str) -> list[Grapheme]:
    """The graphemes of one English word, longest match first; letters the table lacks are skipped.

    A doubled consonant is said once (``ll``, ``tt``); a final ``e`` after a consonant is silent.
    """
    table = english_graphemes()
    text = word.lower()
    out: list[Grapheme] = []
    i = 0
    while i < len(text):
        found = None
        for size in range(min(_longest(), len(text) - i), 0, -1):
            piece = text[i:i + size]
            where = "initial" if i == 0 else ("final" if i + size == len(text) else "medial")
            if where == "final" and piece == "e" and (len(text) <= 2 or text[i - 1] in "aeiouy"):
                where = "medial"  # "be", "see": a spoken final e
            for position in (where, "any"):
                if (piece, position) in table:
                    found = piece, table[piece, position]
                    break
            if found:
                break
        if found is None:
            i += 1  # apostrophes, hyphens, letters outside the table
            continue
        piece, (visemes, weight) = found
        doubled = out and out[-1].text == piece and len(piece) == 1 and piece not in "aeiou"
        if visemes and not doubled:
            out.append(Grapheme(piece, visemes, weight, i))
        i += len(piece)
    return out


def english_units(word: str) -> list[Unit]:
    """The visemes of ``word`` in order with their weights (a grapheme's weight shared by its visemes)."""
    return [Unit(v, g.weight / len(g.visemes), g.text) for g in english_word(word) for v in g.visemes]


def syllable_units(s: Syllable) -> list[Unit]:
    """A syllable's Chinese visemes with weights: the initial by class, then glide, main vowel, ending."""
    visemes = list(s.visemes)
    out: list[Unit] = []
    if s.initial and len(visemes) > 1:
        first = visemes.pop(0)
        out.append(Unit(first, _INITIAL_WEIGHT.get(first, _DEFAULT_INITIAL_WEIGHT), f"{s.pinyin}:initial"))
    roles = final_roles(s.final, len(visemes))
    return out + [Unit(v, FINAL_WEIGHT[r], f"{s.pinyin}:{r}") for v, r in zip(visemes, roles)]


def pinyin_units(token: str) -> list[Unit]:
    """The units of one written pinyin syllable with a tone digit (``hao3``); [] if it is not pinyin."""
    from pypinyin.contrib.tone_convert import to_finals, to_initials

    body = token.lower().rstrip("012345")
    tone = int(token[-1]) if token[-1:].isdigit() else 5
    initial, final = to_initials(body, strict=True), to_finals(body, strict=True)
    try:
        visemes = syllable_visemes(initial, final.replace("ü", "v"))
    except KeyError:
        return []
    return syllable_units(Syllable(token, 0, initial, final, tone, visemes))


def seconds_per_unit(rate: int | None, unit: float = UNIT) -> float:
    """Seconds per unit of weight at ``rate`` words per minute (the reference rate when None)."""
    return unit * REFERENCE_RATE / float(rate or REFERENCE_RATE)
