"""The lids' evened shares kept in the cache (:func:`mpeg4fa.face.lid_folds.even_out_lids`): read back they are
what evening out gives, and any other head or rule is evened out anew under its own name."""
from __future__ import annotations

import numpy as np

from mpeg4fa.face import lid_folds, lids
from mpeg4fa.face.mesh import HeadMesh


def _shares(sheets: dict[int, lids.LidSheet], n: int) -> np.ndarray:
    out = np.zeros((len(sheets), n))
    for row, sheet in enumerate(sheets.values()):
        out[row, sheet.rows] = sheet.ratios
    return out


def test_kept_shares_are_the_evened_ones(generic_head: HeadMesh, tmp_path, monkeypatch):
    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    fresh = lids.build_lids(generic_head)
    kept = sorted((tmp_path / "lid-shares").glob("*.npz"))
    assert len(kept) == 1
    calls = []
    monkeypatch.setattr(lid_folds, "even_out", lambda *a: calls.append(a) or a[2])
    again = lids.build_lids(generic_head)
    assert not calls, "the kept shares were evened out again"
    n = generic_head.n_vertices
    assert np.array_equal(_shares(fresh, n), _shares(again, n))
    assert all(s.ratios[list(s.rows).index(s.point)] == 1.0 for s in again.values())


def test_another_head_or_rule_is_kept_apart(generic_head: HeadMesh, tmp_path, monkeypatch):
    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    rest = generic_head.vertices
    tris = np.array([[0, 1, 2]])
    fields, held, angles = [np.ones(len(rest))], [np.array([0])], np.ones((1, 1))
    base = lid_folds._kept_at(rest, tris, fields, held, angles)
    moved = rest.copy()
    moved[5, 1] += 1e-6
    assert lid_folds._kept_at(moved, tris, fields, held, angles) != base
    assert lid_folds._kept_at(rest, tris, fields, [np.array([1])], angles) != base
    assert lid_folds._kept_at(rest, tris, fields, held, 2 * angles) != base
    assert base.parent == tmp_path / "lid-shares"
