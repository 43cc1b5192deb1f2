"""The face's reach: how far each FAP alone can move this head before its skin folds, and the soft limiter.

The standard lets a stream carry any FAP far past what a face can show (raise_b_midlip at its full
default I range, 3720 MNS, drives the lower lip 59 mm up through the upper one). No smooth skin
follows such motion, so this head saturates, as a rig clamps its blend weights and a muscle stops:
each FAP and sign has a **reach** (the largest value that still passes the crease criterion,
:meth:`.creases.Crease.ok`, measured by ``tools/measure_reach.py`` into ``data/reach.csv``), and past a
**knee** (the largest value ordinary use asks for: visemes, expressions, blinks, the named brow
poses, real streams, the tracker's training streams; at least :data:`EXACT_UP_TO`) the shown value eases
toward the **limit** (the reach less :data:`MARGIN`) never past it. Up to the knee values pass unchanged.

This is the face layer's choice, not the stream's: decoded values, their clamp
(:mod:`mpeg4fa.decoded`) and the FAPU semantics are untouched; only what this head shows saturates.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np

from mpeg4fa.spec import N_FAPS

MARGIN = 0.05
"""The limit is the measured reach less this share of it: a value the limiter gives never sits on a fold's edge."""
EXACT_UP_TO = 300.0
"""Every FAP shows value x FAPU exactly up to at least this magnitude, however little ordinary use asks of it:
the conformance suite's semantics vectors pose each FAP alone at about 200 units, and its reference model is
checked against this face engine at 300 (tests/conformance/test_reference.py)."""


@dataclass(frozen=True)
class Reach:
    """Per FAP and sign (row 0 positive, row 1 negative magnitudes, shape (2, 68)): identity up to
    ``knee``, then an ease that stays below ``limit``; ``inf`` where a FAP is not limited."""

    knee: np.ndarray
    limit: np.ndarray

    def limited(self) -> np.ndarray:
        """(2, 68) bool: where the limiter acts at all."""
        return np.isfinite(self.limit)


def limits(ok: float, fold: float, used: float) -> tuple[float, float]:
    """``(knee, limit)`` for one FAP and sign from its measured reaches and ordinary use (``inf``: the
    whole range passes). The limit is the reach of the whole crease criterion (``ok``) less the margin;
    where that is within ordinary use (a FAP whose strain outgrows its floor from the start, at a
    constant ratio), the reach without folds (``fold``) instead. The knee is ordinary use, at least
    :data:`EXACT_UP_TO`. No limit (``inf, inf``) where the range passes or where folds start at or below
    the knee: saturating there would change what the face shows every day."""
    used = max(used, EXACT_UP_TO)
    for reach in (ok, fold):
        limit = reach * (1.0 - MARGIN)
        if not np.isfinite(reach):
            return np.inf, np.inf
        if limit > used:
            return used, limit
    return np.inf, np.inf


def ease(magnitude: np.ndarray, knee: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """``magnitude`` up to ``knee`` as it is, beyond it ``knee + span * tanh(excess / span)``
    (span = limit - knee): C1 at the knee (slope 1), rising, and below ``limit`` (at it only where
    tanh rounds to 1, some 19 spans past the knee)."""
    span = limit - knee
    over = magnitude > knee
    out = np.array(magnitude, dtype=np.float64, copy=True)
    if np.any(over):
        s = span[over]
        out[over] = knee[over] + s * np.tanh((magnitude[over] - knee[over]) / s)
    return out


def saturate(values: np.ndarray, reach: Reach | None = None) -> np.ndarray:
    """The values this head shows for ``values`` (..., 68): each FAP eased into its reach."""
    reach = reach or load_reach()
    v = np.asarray(values, dtype=np.float64)
    negative = v < 0
    knee = np.where(negative, reach.knee[1], reach.knee[0])
    limit = np.where(negative, reach.limit[1], reach.limit[0])
    act = np.isfinite(limit)
    if not np.any(act & (np.abs(v) > knee)):
        return v
    shown = np.where(act, ease(np.abs(v), np.where(act, knee, 0.0), np.where(act, limit, 1.0)), np.abs(v))
    return np.where(negative, -shown, shown)


def _number(text: str) -> float:
    return float(text) if text.strip() else np.inf


def table() -> list[dict[str, float | str]]:
    """The rows of ``data/reach.csv`` (``#`` lines are its header: how it was measured), numbers as floats
    (``inf`` where empty), ``name`` as text."""
    with (resources.files("mpeg4fa.face") / "data" / "reach.csv").open(encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    return [{k: (v if k == "name" else _number(v)) for k, v in r.items()} for r in rows]


@lru_cache(maxsize=1)
def load_reach() -> Reach:
    """The limiter's table from :func:`table`; FAPs not in it are not limited."""
    knee, limit = np.full((2, N_FAPS), np.inf), np.full((2, N_FAPS), np.inf)
    for r in table():
        i = int(r["fap"]) - 1
        knee[0, i], limit[0, i] = r["knee_pos"], r["limit_pos"]
        knee[1, i], limit[1, i] = r["knee_neg"], r["limit_neg"]
    knee.flags.writeable = limit.flags.writeable = False
    return Reach(knee=knee, limit=limit)


def no_reach() -> Reach:
    """A table that limits nothing (to measure the face without its limiter)."""
    return Reach(knee=np.full((2, N_FAPS), np.inf), limit=np.full((2, N_FAPS), np.inf))
