"""Phonemes to visemes: English (espeak-ng's phoneme mnemonics -> the 14 MPEG-4 visemes) and
Mandarin (pinyin syllables -> Chinese visemes, see :mod:`.mandarin`); every other language goes
through IPA and articulatory features (:mod:`.ipa`), held to this English table on English speech.

The English table is data (``spec/english_visemes.csv``). A pause (a mnemonic starting
with ``_``) is ``none``; a ``=`` row means "the previous phoneme continues" (espeak's
``;`` modifier). A phoneme the table does not know fails loudly, naming it and where
it was spoken: a silently dropped phoneme is a mouth that stops moving.
"""
from __future__ import annotations

from functools import lru_cache

from mpeg4fa.spec import VISEME_PROFILES
from mpeg4fa.spec._load import read_table
from mpeg4fa.speech.errors import TTSError
from mpeg4fa.speech.tts.base import Event

CONTINUE = "="
PAUSE = "none"


@lru_cache(maxsize=None)
def english_table() -> dict[str, str]:
    """espeak-ng mnemonic (stress marks stripped) -> MPEG-4 viseme name, or ``=``."""
    rows = read_table("english_visemes.csv", "phoneme,viseme,example")
    table = {}
    for row in rows:
        viseme = row["viseme"]
        if viseme != CONTINUE and viseme not in VISEME_PROFILES["mpeg4"]:
            raise ValueError(f"english_visemes.csv: {row['phoneme']!r} maps to unknown viseme {viseme!r}")
        if row["phoneme"] in table:
            raise ValueError(f"english_visemes.csv: {row['phoneme']!r} is listed twice")
        table[row["phoneme"]] = viseme
    return table


def english_viseme(phoneme: str) -> str:
    """The viseme of one espeak mnemonic (stress marks ' and , ignored); KeyError if unmapped."""
    bare = phoneme.lstrip("',")
    if bare.startswith("_") or not bare:
        return PAUSE
    return english_table()[bare]


def english_visemes(phonemes: list[Event]) -> list[tuple[str, Event]]:
    """(viseme, phoneme event) for each phoneme, ``=`` rows folded into their predecessor's viseme.

    Raises :class:`TTSError` listing every phoneme the table lacks.
    """
    out: list[tuple[str, Event]] = []
    missing: dict[str, float] = {}
    for event in phonemes:
        try:
            viseme = english_viseme(event.text)
        except KeyError:
            missing.setdefault(event.text, event.start)
            continue
        if viseme == CONTINUE:
            viseme = out[-1][0] if out else PAUSE
        out.append((viseme, event))
    if missing:
        listed = ", ".join(f"{p!r} (first at {t:.3f} s)" for p, t in missing.items())
        raise TTSError(f"no viseme for the phonemes {listed}", where="spec/english_visemes.csv",
                       hint="add a row for each (phoneme,viseme,example)")
    return out
