"""Shared helpers for the FBA codec tests: real vectors, stream generators, comparisons, a hang guard."""
from __future__ import annotations

import os
import signal
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path
from typing import Iterator

import numpy as np
import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from mpeg4fa import spec
from mpeg4fa.fba import FapStream, decode

VECTORS = Path(__file__).resolve().parents[2].parent / "shared" / "vectors"
FBA_VECTORS = VECTORS / "fba"
SKIP_REASON = f"../shared/vectors not present: the real FBA streams are read from {FBA_VECTORS}"


def real_vector_paths() -> list[Path]:
    """Every real FBA stream (``*.fba`` / ``*.FBA``), sorted; empty when the folder is absent."""
    if not FBA_VECTORS.is_dir():
        return []
    return sorted(p for p in FBA_VECTORS.rglob("*") if p.is_file() and p.suffix.lower() == ".fba")


def vector_id(path: Path) -> str:
    return path.relative_to(FBA_VECTORS).as_posix()


def vector_path(name: str) -> Path:
    """The path of one real vector (e.g. ``en/vote-unlock.FBA``); skips the test when absent."""
    path = FBA_VECTORS / name
    if not path.is_file():
        pytest.skip(f"{SKIP_REASON} ({name} missing)")
    return path


@lru_cache(maxsize=None)
def vector_bytes(name: str) -> bytes:
    return vector_path(name).read_bytes()


@lru_cache(maxsize=None)
def vector_stream(name: str) -> FapStream:
    """The decoded stream of a real vector, decoded once per session (treat it as read-only)."""
    return decode(vector_bytes(name))


# ---- comparisons -------------------------------------------------------------------------
VALUE_FIELDS = ("fap_mask", "fap_values", "viseme", "expression", "bap_mask", "bap_values", "object_mask")
FRAME_FIELDS = VALUE_FIELDS + ("timestamps", "skip", "start_code", "bits")


def assert_streams_equal(a: FapStream, b: FapStream, fields=FRAME_FIELDS, n: int | None = None) -> None:
    """Arrays of ``a`` equal those of ``b`` (only the first ``n`` frames of ``b`` when given)."""
    n = len(b) if n is None else n
    assert len(a) == n
    for name in fields:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name)[:n], err_msg=name)


def on_grid(s: FapStream) -> dict[str, np.ndarray]:
    """Value arrays with every frame repeated (skip + 1) times: the stream on its frame grid."""
    idx = np.repeat(np.arange(len(s)), np.asarray(s.skip, dtype=np.int64) + 1)
    return {name: getattr(s, name)[idx] for name in VALUE_FIELDS}


def assert_same_on_grid(a: FapStream, b: FapStream) -> None:
    ga, gb = on_grid(a), on_grid(b)
    for name in VALUE_FIELDS:
        np.testing.assert_array_equal(ga[name], gb[name], err_msg=name)


def expected_timestamps(skip: np.ndarray, fps: float, t0: float = 0.0) -> np.ndarray:
    slots = np.concatenate([[0], np.cumsum(np.asarray(skip, dtype=np.int64)[:-1] + 1)])
    return t0 + slots / fps


# ---- quantiser steps ---------------------------------------------------------------------
QUANT_STEP = spec.QUANT_STEP.astype(np.int64)
BAP_QUANT_STEP = spec.BAP_QUANT_STEP.astype(np.int64)
BAP_PRED_SCALE = spec.BAP_PRED_SCALE.astype(np.int64)
GROUP_SLICES = spec.FAP_GROUP_SLICES
GROUP_SIZES = [b - a for a, b in GROUP_SLICES]


def fap_qstep(fap_quant: int) -> np.ndarray:
    """Step of every FAP column (0 for columns 0, 1 and when fap_quant is 0)."""
    q = QUANT_STEP * fap_quant
    q[:2] = 0
    return q


def bap_qstep(bap_quant: int) -> np.ndarray:
    return BAP_QUANT_STEP * BAP_PRED_SCALE[bap_quant]


def level_bound(scale: int) -> int:
    """Largest |level| to generate so that any frame-to-frame change fits the widest range 31*60/scale."""
    return (1860 // max(scale, 1) - 2) // 2


def value_bound(qstep: np.ndarray, scale: int) -> np.ndarray:
    """Per-column |value| bound for generated data: level_bound levels of the column's step (or of 1)."""
    return level_bound(scale) * np.maximum(qstep, 1)


# ---- generated streams -------------------------------------------------------------------
def _random_face(s: FapStream, rng: np.random.Generator, mask: np.ndarray, fap_quant: int) -> None:
    n = len(s)
    s.fap_mask[:] = mask
    low = mask.copy()
    low[:2] = False
    lim = value_bound(fap_qstep(fap_quant), fap_quant)
    s.fap_values[:] = np.where(low[None, :], rng.integers(-lim, lim + 1, size=(n, 68)), 0)
    if mask[0]:
        s.viseme[:] = np.stack([rng.integers(0, 15, n), rng.integers(0, 15, n), rng.integers(0, 64, n),
                                rng.integers(0, 2, n)], axis=1)
    if mask[1]:
        s.expression[:] = np.stack([rng.integers(0, 7, n), rng.integers(0, 64, n), rng.integers(0, 7, n),
                                    rng.integers(0, 64, n), rng.integers(0, 2, n), rng.integers(0, 2, n)], axis=1)


def _random_body(s: FapStream, rng: np.random.Generator, mask: np.ndarray, bap_quant: int) -> None:
    s.bap_mask[:] = mask
    lim = value_bound(bap_qstep(bap_quant), int(BAP_PRED_SCALE[bap_quant]))
    s.bap_values[:] = np.where(mask[None, :], rng.integers(-lim, lim + 1, size=(len(s), 296)), 0)


def make_stream(seed: int, n: int, *, fap_mask=None, fap_quant: int = 1, bap_mask=None, bap_quant: int = 1,
                fps: float = 25.0, hold: float = 0.2) -> FapStream:
    """A generated stream: face when ``fap_mask`` is given, body when ``bap_mask`` is given.

    Values stay well inside the coded ranges; a fraction ``hold`` of the frames repeat the frame before.
    """
    rng = np.random.default_rng(seed)
    obj = (1 if fap_mask is not None else 0) | (2 if bap_mask is not None else 0)
    assert obj, "give a face mask, a body mask or both"
    s = FapStream.empty(n, object_mask=obj)
    if fap_mask is not None:
        _random_face(s, rng, np.asarray(fap_mask, dtype=bool), fap_quant)
    if bap_mask is not None:
        _random_body(s, rng, np.asarray(bap_mask, dtype=bool), bap_quant)
    for k in range(1, n):
        if rng.random() < hold:
            for name in ("fap_values", "viseme", "expression", "bap_values"):
                getattr(s, name)[k] = getattr(s, name)[k - 1]
    s.source_fps = fps
    s.timestamps[:] = np.arange(n) / fps
    return s


def mask_from_types(rng: np.random.Generator, types) -> np.ndarray:
    """A 68-entry FAP mask that agrees with per-group mask types (0 none, 3 all, 1/2 a random subset)."""
    mask = np.zeros(68, dtype=bool)
    for (a, b), t in zip(GROUP_SLICES, types):
        if t == 3:
            mask[a:b] = True
        elif t in (1, 2):
            mask[a:b] = rng.random(b - a) < 0.5
    return mask


# hypothesis strategies ------------------------------------------------------------------
EXAMPLES_SCALE = float(os.environ.get("FBA_TEST_EXAMPLES_SCALE", "1"))
"""Multiplies every max_examples of these tests (e.g. 20 for a long bug hunt); 1 keeps the suite fast."""


RANDOM = EXAMPLES_SCALE != 1 or bool(os.environ.get("FBA_TEST_RANDOM"))
"""By default every run draws the same examples (a deterministic suite); a bug hunt draws new ones."""


def examples(n: int) -> int:
    return max(1, int(n * EXAMPLES_SCALE))


def hyp_settings(n: int) -> settings:
    """Hypothesis settings for ``n`` examples (times FBA_TEST_EXAMPLES_SCALE), no deadline."""
    return settings(max_examples=examples(n), deadline=None, derandomize=not RANDOM,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


seeds = st.integers(0, 2**32 - 1)
mask_types_st = st.lists(st.integers(0, 3), min_size=10, max_size=10)


def assert_close_to_input(decoded: FapStream, source: FapStream, fap_quant: int, bap_quant: int) -> None:
    """Decoded values are within qstep//2 of the input on the frame grid (exact when qstep is 0)."""
    g = on_grid(decoded)
    src_idx = np.arange(len(source))  # the source has no skipped frames unless it says so
    src_idx = np.repeat(src_idx, np.asarray(source.skip, dtype=np.int64) + 1)
    np.testing.assert_array_equal(g["fap_mask"], source.fap_mask[src_idx])
    np.testing.assert_array_equal(g["bap_mask"], source.bap_mask[src_idx])
    fq, bq = fap_qstep(fap_quant), bap_qstep(bap_quant)
    dv = np.abs(g["fap_values"].astype(np.int64) - source.fap_values[src_idx])
    assert (dv <= fq // 2).all(), f"FAP values off by up to {dv.max()}"
    db = np.abs(g["bap_values"].astype(np.int64) - source.bap_values[src_idx])
    assert (db <= bq // 2).all(), f"BAP values off by up to {db.max()}"
    fm = source.fap_mask[src_idx]
    q = fap_quant
    high_level = ((0, source.viseme, g["viseme"], (2,)), (1, source.expression, g["expression"], (1, 3)))
    for col, src, dec, fields in high_level:  # FAP 1 / FAP 2: selects and flags exact, blend/intensities quantised
        rows = fm[:, col]
        exact = [k for k in range(src.shape[1]) if k not in fields]
        np.testing.assert_array_equal(dec[rows][:, exact], src[src_idx][rows][:, exact])
        d = np.abs(dec[rows][:, list(fields)] - src[src_idx][rows][:, list(fields)])
        assert (d <= q // 2).all()


# ---- hang guard --------------------------------------------------------------------------
class Hang(Exception):
    pass


@contextmanager
def time_limit(seconds: int) -> Iterator[None]:
    """Fail with :class:`Hang` when the block runs longer than ``seconds`` (SIGALRM, main thread)."""
    if not hasattr(signal, "SIGALRM"):
        yield
        return

    def on_alarm(signum, frame):
        raise Hang(f"took more than {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
