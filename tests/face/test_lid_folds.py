"""The lids' evened shares kept in the cache (:func:`mpeg4fa.face.lid_folds.even_out_lids`): read back they are
what evening out gives (how they are named: tests/face/test_kept.py)."""
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

