"""Phonemes to visemes: English (espeak-ng's phoneme mnemonics -> the 14 MPEG-4 visemes) and
Mandarin (pinyin syllables -> Chinese visemes, see :mod:`.mandarin`); every other language goes
through IPA and articulatory features (:mod:`.ipa`), held to this English table on English speech.

The English table is data (``spec/english_visemes.csv``). A pause (a mnemonic starting
with ``_``) is ``none``; a ``=`` row means "the previous phoneme continues" (espeak's
``;`` modifier).

Every phoneme gets a mouth: the table is the preferred choice, not the only one. A mnemonic it
lacks (``l#`` in "Bokhl", ``O``) is read as the IPA espeak-ng itself gives it
(``spec/english_ipa.csv``, every mnemonic of every English phoneme table, written by
``tools/english_ipa.py``) and mapped by its features like any other language (:mod:`.ipa`), its
parts sharing the phoneme's time as a diphthong's do. A mnemonic missing from both tables (a
voice newer than the table) is read as IPA letters and the nearest viseme
(:func:`.ipa.nearest`); such guesses are counted in one warning per encode
(:func:`.ipa.phoneme_fallbacks`), never an error.
"""
from __future__ import annotations

from functools import lru_cache

from mpeg4fa.spec import VISEME_PROFILES
from mpeg4fa.spec._load import read_table
from mpeg4fa.speech.ipa import CONTINUE, PAUSE, phoneme_fallbacks, phoneme_visemes, split_event
from mpeg4fa.speech.tts.base import Event

__all__ = ["CONTINUE", "PAUSE", "english_table", "english_ipa", "english_viseme", "english_visemes"]


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


@lru_cache(maxsize=None)
def english_ipa() -> dict[str, str]:
    """``spec/english_ipa.csv``: espeak-ng mnemonic -> the IPA espeak-ng names it with (checked: once each)."""
    table: dict[str, str] = {}
    for line, row in enumerate(read_table("english_ipa.csv", "phoneme,ipa,table"), start=2):
        if not row["phoneme"] or not row["ipa"] or row["phoneme"] in table:
            raise ValueError(f"spec/english_ipa.csv:{line}: {row['phoneme']!r} must have an IPA name, listed once")
        table[row["phoneme"]] = row["ipa"]
    return table


def _bare(phoneme: str) -> str:
    return phoneme.lstrip("',")


def _parts(bare: str) -> tuple[list[tuple[str, str]], list[str] | str]:
    """(segment, viseme) parts of a mnemonic the English table lacks, and what was guessed: the characters
    of its IPA no table knows, or (a mnemonic in no table) a phrase saying so."""
    ipa = english_ipa().get(bare)
    if ipa is None:  # in no table: its letters read as IPA (espeak's ASCII mnemonics are aliases there)
        return phoneme_visemes(bare)[0], "a mnemonic of no English phoneme table"
    return phoneme_visemes(ipa)


def english_viseme(phoneme: str) -> str:
    """The viseme of one espeak mnemonic (stress marks ' and , ignored): the table's, else the first part's
    by IPA features (a diphthong's nucleus); ``=`` when the previous phoneme continues."""
    bare = _bare(phoneme)
    if bare.startswith("_") or not bare:
        return PAUSE
    if bare in english_table():
        return english_table()[bare]
    return _parts(bare)[0][0][1]


def english_visemes(phonemes: list[Event]) -> list[tuple[str, Event]]:
    """(viseme, phoneme event) for each phoneme, ``=`` rows folded into their predecessor's viseme.

    A mnemonic the table lacks goes by its IPA features (see the module docstring); when it has
    several parts (``aI@``) each gets an event of its own, ``name:segment``, over its share of the time.
    """
    out: list[tuple[str, Event]] = []
    with phoneme_fallbacks("espeak (English)") as log:
        for event in phonemes:
            bare = _bare(event.text)
            if bare.startswith("_") or not bare:
                out.append((PAUSE, event))
                continue
            viseme = english_table().get(bare)
            if viseme is not None:
                out.append((out[-1][0] if out else PAUSE, event) if viseme == CONTINUE else (viseme, event))
                continue
            parts, unknown = _parts(bare)
            if unknown:
                log.note(event.text, unknown, "".join(symbol for symbol, _ in parts))
            if len(parts) == 1 and parts[0][1] == CONTINUE:
                out.append((out[-1][0] if out else PAUSE, event))
                continue
            for label, v, start, end in split_event(event, parts):
                out.append((v, event if label == event.text else Event(event.kind, start, end, label, event.position)))
    return out
