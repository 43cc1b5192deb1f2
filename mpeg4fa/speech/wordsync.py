"""Visemes inside words the engine only times at their starts: estimate, then resynchronise.

This is the seed's two-thread scheme run offline. The speech side reports when each word
starts; the animation side plays the word's visemes with durations estimated from the
spelling (:mod:`.graphemes`) and the speech rate. At the next word boundary the animation
is back in step: a word whose estimate runs past the next boundary is compressed to fit;
one that ends early is stretched to the boundary, unless the gap is longer than ``pause``
seconds: then its visemes keep their estimated lengths and the mouth returns to neutral
(the timeline closes to the ``none`` viseme in a gap) until the next word.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

PAUSE = 0.12  # seconds: a longer gap between the estimate's end and the next word is a pause


@dataclass(frozen=True)
class Unit:
    """One viseme of a word before timing: its name, duration weight and what it was read from."""

    viseme: str
    weight: float
    label: str


def resync(starts: Sequence[float], words: Sequence[Sequence[Unit]], end: float, seconds_per_unit: float,
           *, pause: float = PAUSE) -> list[tuple[Unit, float, float]]:
    """(unit, start, end) for every unit of every word; word ``k`` starts at ``starts[k]`` and
    must be over by the next word's start (``end`` for the last word)."""
    if len(starts) != len(words):
        raise ValueError(f"{len(starts)} word starts for {len(words)} words")
    out: list[tuple[Unit, float, float]] = []
    bounds = list(starts[1:]) + [end]
    for start, stop, units in zip(starts, bounds, words):
        weights = [max(u.weight, 0.0) for u in units]
        total = sum(weights)
        room = stop - start
        if not units or total <= 0 or room <= 0:
            continue
        estimate = total * seconds_per_unit
        fits = room - estimate <= pause  # compress or stretch to the boundary; else pause after
        finish = stop if fits else start + estimate
        edges = start + (finish - start) * np.cumsum([0.0] + weights) / total
        edges[-1] = finish  # exactly the next boundary, so neighbouring words never overlap
        out += [(unit, float(a), float(b)) for unit, a, b in zip(units, edges[:-1], edges[1:])]
    return out
