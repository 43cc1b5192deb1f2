"""The face's reach (:mod:`mpeg4fa.face.reach`, issue 29 item 3): each FAP eases into the largest value this
head shows without folding, and values in ordinary use are shown exactly as they are.

The table (``face/data/reach.csv``) is measured by ``tools/measure_reach.py``; what the full range does with
and without it is in tests/face/test_creases.py.
"""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.face import creases, reach
from mpeg4fa.face.quality import used_magnitudes
from mpeg4fa.spec import N_FAPS
from mpeg4fa.spec.profiles import EXPRESSION_PROFILES, VISEME_PROFILES, expression_blend

ROOT = Path(__file__).resolve().parents[2]


def _tool(name: str):
    spec = importlib.util.spec_from_file_location(f"{name}_for_reach", ROOT / "tools" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_ease_is_identity_then_smooth_rising_and_below_the_limit():
    knee, limit = np.array([300.0]), np.array([700.0])
    x = np.linspace(0, 5000, 20001)
    y = np.array([reach.ease(np.array([v]), knee, limit)[0] for v in x])
    assert np.array_equal(y[x <= 300], x[x <= 300])
    assert np.all(np.diff(y) > 0) and y.max() < 700 and y[-1] > 699.9
    slope = np.diff(y) / np.diff(x)
    at = np.searchsorted(x, 300.0)
    assert abs(slope[at] - 1.0) < 1e-3 and abs(slope[at - 1] - 1.0) < 1e-12  # C1 at the knee
    assert np.max(np.abs(np.diff(slope))) < 1e-3  # no kink anywhere


def test_saturate_acts_per_sign_and_leaves_unlimited_faps():
    table = reach.load_reach()
    limited = table.limited()
    assert limited.any(), "the table limits nothing"
    v = np.zeros(N_FAPS)
    fap = int(np.flatnonzero(limited[0])[0])
    v[fap] = 1e6
    assert reach.saturate(v)[fap] <= table.limit[0, fap]  # never past it (tanh rounds to 1 this far out)
    v[fap] = table.knee[0, fap] + 100.0
    assert table.knee[0, fap] < reach.saturate(v)[fap] < v[fap]
    free = int(np.flatnonzero(~limited[0] & ~limited[1])[0])
    v[free] = -1e6
    assert reach.saturate(v)[free] == -1e6
    assert np.array_equal(reach.saturate(v, reach.no_reach()), v)


def test_table_rows_follow_the_rule():
    """knee and limit as :func:`reach.limits` makes them from the measured reaches and ordinary use."""
    for r in reach.table():
        for side in ("pos", "neg"):
            ok = min(r[f"ok_fap_{side}"], r[f"ok_arkit_{side}"])
            fold = min(r[f"fold_fap_{side}"], r[f"fold_arkit_{side}"])
            assert ok <= fold
            knee, limit = reach.limits(ok, fold, r[f"used_{side}"])
            assert (r[f"knee_{side}"], r[f"limit_{side}"]) == pytest.approx((knee, limit)), (r["fap"], side)


def _ordinary_rows() -> dict[str, np.ndarray]:
    rows = {"visemes": np.array([p for s in VISEME_PROFILES.values() for p in s.values()]),
            "expressions 63 x 2": np.array([expression_blend(e, 63, e, 63) for e in EXPRESSION_PROFILES]),
            "brows named": np.array([p for k, p in creases.crease_poses().items()
                                     if k in ("brows x2 up", "brows x2 down", "brows 400", "squeeze x2")])}
    used = np.zeros((2, N_FAPS))
    for fap, (pos, neg) in used_magnitudes().items():
        used[:, fap - 1] = pos, -neg
    rows["streams and profiles"] = used
    blink = np.zeros((1, N_FAPS))
    blink[0, 18:20] = _tool("track_loop").BLINK_PEAK
    rows["blinks"] = blink
    return rows


@pytest.mark.parametrize("source", ["visemes", "expressions 63 x 2", "brows named", "streams and profiles", "blinks"])
def test_ordinary_use_is_shown_unchanged(source):
    rows = _ordinary_rows()[source]
    assert np.array_equal(reach.saturate(rows), rows)


def test_tracker_training_streams_are_shown_unchanged():
    """The tracker learns from renders of this face: its training streams must render as before."""
    train = _tool("train_tracker")
    for seed, swept in sorted({(seed, swept) for _, seed, _, swept in train.stream_plan()}):
        values = train.training_values(seed, 20.0, swept)
        assert np.array_equal(reach.saturate(values), values), (seed, swept)


def test_vertices_do_not_move_in_ordinary_use(generic_face):
    """Posed with and without the limiter, the named brow poses and the expressions at 63 x 2 put every
    vertex in the same place (0.0 mm)."""
    free = generic_face.unlimited()
    rows = _ordinary_rows()
    for row in (*rows["brows named"], *rows["expressions 63 x 2"]):
        assert np.array_equal(generic_face.pose_values(row).vertices, free.pose_values(row).vertices)


def test_the_limiter_is_on_by_default_and_off_when_asked(generic_face):
    v = np.zeros(N_FAPS)
    v[4] = creases.full_range_value(5)  # raise_b_midlip 3720 MNS
    assert generic_face.saturates and not generic_face.unlimited().saturates
    limited = generic_face.pose_values(v).feature_points
    free = generic_face.unlimited().pose_values(v).feature_points
    assert np.abs(limited - free).max() > 10.0
