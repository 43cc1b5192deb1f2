"""Relative lengths of a Mandarin syllable's parts, from ``spec/mandarin_weights.csv``: ours, not the standard's.

An engine that reports words but no phonemes (pyttsx3), or a syllable whose
phonemes the engine does not time, still needs each viseme's share of the
syllable. Encoder and tests read the shares from one data file, on a scale where
the main vowel is 1.
"""
from __future__ import annotations

import math

from mpeg4fa.spec._load import check, read_table
from mpeg4fa.spec.profiles import CHINESE_VISEMES

__all__ = ["MANDARIN_PART_WEIGHT", "MANDARIN_INITIAL_WEIGHT", "MANDARIN_DEFAULT_INITIAL_WEIGHT"]

_PARTS = ("initial", "glide", "main", "ending")


def _weights() -> dict[tuple[str, str], float]:
    table: dict[tuple[str, str], float] = {}
    initials = {v.name for v in CHINESE_VISEMES if v.kind in ("initial", "both")}
    for line, row in enumerate(read_table("mandarin_weights.csv", "part,viseme,weight,note"), start=2):
        where = f"mandarin_weights.csv line {line}"
        part, viseme = row["part"], row["viseme"]
        check(part in _PARTS, f"{where}: part {part!r} not in {_PARTS}")
        check(not viseme or (part == "initial" and viseme in initials),
              f"{where}: {viseme!r} is no initial viseme of chinese_visemes.csv (only initials have their own)")
        try:
            weight = float(row["weight"])
        except ValueError:
            weight = math.nan
        check(math.isfinite(weight) and weight > 0, f"{where}: weight {row['weight']!r} must be a number > 0")
        check((part, viseme) not in table, f"{where}: {part} {viseme} is listed twice")
        table[(part, viseme)] = weight
    check(all((part, "") in table for part in _PARTS), f"mandarin_weights.csv needs a row for each of {_PARTS}")
    check(table[("main", "")] == 1.0, "mandarin_weights.csv: the main vowel is the unit (1.0)")
    return table


_TABLE = _weights()
MANDARIN_PART_WEIGHT: dict[str, float] = {part: _TABLE[(part, "")] for part in ("glide", "main", "ending")}
"""A final's parts by role (``glide``, ``main``, ``ending``): the main vowel is 1, a glide passes quickly."""
MANDARIN_INITIAL_WEIGHT: dict[str, float] = {v: w for (part, v), w in _TABLE.items() if part == "initial" and v}
"""Initials whose length differs from the default, by viseme (``bpm`` 0.7, ``dtnl`` 0.35, ``f`` 0.55)."""
MANDARIN_DEFAULT_INITIAL_WEIGHT: float = _TABLE[("initial", "")]
"""Weight of any other initial."""
del _TABLE
