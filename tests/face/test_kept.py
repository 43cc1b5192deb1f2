"""Arrays kept in the user cache (:func:`mpeg4fa.face.kept.kept`): read back they are what was derived, any other
input or rule is derived anew under its own name, and a torn file or a cache that cannot be written costs only
the time."""
from __future__ import annotations

import os

import numpy as np
import pytest

from mpeg4fa.face import kept as kept_module, lid_folds
from mpeg4fa.face.kept import kept


def test_read_back_is_what_was_derived(tmp_path, monkeypatch):
    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    calls = []
    a = np.arange(6.0).reshape(2, 3)

    def derive():
        calls.append(1)
        return a * 2

    first = kept("things", (a,), (kept_module,), derive)
    again = kept("things", (a,), (kept_module,), derive)
    assert len(calls) == 1 and np.array_equal(first, again) and np.array_equal(again, a * 2)
    assert len(list((tmp_path / "things").glob("*.npz"))) == 1


def test_another_input_rule_or_kind_is_kept_apart(tmp_path, monkeypatch):
    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    rest = np.zeros((4, 3))
    base = kept_module._path("things", (rest, "label"), (kept_module,))
    moved = rest.copy()
    moved[2, 1] += 1e-9
    assert kept_module._path("things", (moved, "label"), (kept_module,)) != base
    assert kept_module._path("things", (rest.astype(np.float32), "label"), (kept_module,)) != base
    assert kept_module._path("things", (rest, "other"), (kept_module,)) != base
    assert kept_module._path("things", (rest, "label"), (kept_module, lid_folds)) != base
    assert kept_module._path("others", (rest, "label"), (kept_module,)).parent == tmp_path / "others"
    assert base.parent == tmp_path / "things"


def test_a_torn_file_is_derived_again(tmp_path, monkeypatch):
    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    a = np.ones(3)
    path = kept_module._path("things", (a,), (kept_module,))
    path.parent.mkdir(parents=True)
    path.write_bytes(b"PK\x03\x04 not a whole file")
    assert np.array_equal(kept("things", (a,), (kept_module,), lambda: a + 1), a + 1)
    assert np.array_equal(kept("things", (a,), (kept_module,), lambda: a * 0), a + 1)  # written anew
    with path.open("wb") as f:  # a foreign file: a plain .npy where the .npz should be
        np.save(f, a * 7)
    assert np.array_equal(kept("things", (a,), (kept_module,), lambda: a + 2), a + 2)
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name]  # no part-written file left behind


def test_no_writable_cache_derives_every_time(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("a file where the cache folder would be")
    monkeypatch.setenv("MPEG4FA_CACHE", str(blocked))
    a = np.ones(3)
    assert np.array_equal(kept("things", (a,), (kept_module,), lambda: a + 1), a + 1)
    assert np.array_equal(kept("things", (a,), (kept_module,), lambda: a + 2), a + 2)


def test_a_kind_keeps_its_most_recently_used_files(tmp_path, monkeypatch):
    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    monkeypatch.setattr(kept_module, "KEEP", 5)
    folder = tmp_path / "things"
    for i in range(8):
        kept("things", (np.full(2, float(i)),), (kept_module,), lambda: np.zeros(1))
        newest = kept_module._path("things", (np.full(2, float(i)),), (kept_module,))
        os.utime(newest, ns=(i * 10**9, i * 10**9))  # one second apart, whatever the file system's clock
        if i == 4:  # the first file used again: it stays
            first = kept_module._path("things", (np.full(2, 0.0),), (kept_module,))
            kept("things", (np.full(2, 0.0),), (kept_module,), lambda: pytest.fail("derived again"))
            os.utime(first, ns=(45 * 10**8, 45 * 10**8))
    names = {p.name for p in folder.glob("*.npz")}
    assert len(names) == 5
    assert kept_module._path("things", (np.full(2, 0.0),), (kept_module,)).name in names
    assert kept_module._path("things", (np.full(2, 7.0),), (kept_module,)).name in names
    assert kept_module._path("things", (np.full(2, 1.0),), (kept_module,)).name not in names


def test_a_sparse_matrix_reads_back_exactly(tmp_path, monkeypatch):
    """The rig's Sibson weights (:func:`mpeg4fa.face.rig._sibson`) are kept this way: read back, the same
    matrix to the bit; a file that holds something else is derived again."""
    import scipy.sparse as sp

    from mpeg4fa.face.kept import kept_sparse

    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    m = sp.random(40, 9, density=0.2, random_state=1, format="csc")
    calls = []

    def derive():
        calls.append(1)
        return m

    first = kept_sparse("weights", (np.arange(3.0),), (kept_module,), derive)
    again = kept_sparse("weights", (np.arange(3.0),), (kept_module,), derive)
    assert len(calls) == 1 and again.shape == (40, 9) and again.dtype == m.dtype
    assert (first != m).nnz == 0 and np.array_equal(again.toarray(), m.toarray())
    path = kept_module._path("weights", (np.arange(3.0),), (kept_module,))
    np.savez(path, array=np.zeros(2))  # a dense array under the matrix's name
    assert np.array_equal(kept_sparse("weights", (np.arange(3.0),), (kept_module,), derive).toarray(), m.toarray())
    assert len(calls) == 2


def test_the_rig_built_from_kept_weights_is_the_rig(generic_face, tmp_path, monkeypatch):
    from mpeg4fa.face import rig as rig_module

    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    mesh = generic_face.mesh
    skin = mesh.part("skin")
    fps = [i for i, v in enumerate(mesh.fp_vertex) if skin.start <= v < skin.stop]
    derived = rig_module._sibson(mesh, skin, fps, None)  # the cache is empty: derived and kept
    read = rig_module._sibson(mesh, skin, fps, None)
    assert list((tmp_path / "sibson").glob("*.npz"))
    assert derived[0] == read[0] and (derived[1] != read[1]).nnz == 0
    # the same as the weights without the cache (the rule as it was before it was kept)
    from mpeg4fa.face.sibson import cage_points, natural_neighbour_weights

    sites = mesh.vertices[mesh.fp_vertex[read[0]]]
    queries = mesh.vertices[skin]
    plain = natural_neighbour_weights(np.concatenate([sites, cage_points(np.concatenate([sites, queries]))]),
                                      queries)[:, :len(read[0])].tocsc()
    assert (plain != read[1]).nnz == 0


def test_a_foreign_sparse_file_is_derived_again(tmp_path, monkeypatch):
    import scipy.sparse as sp

    from mpeg4fa.face.kept import kept_sparse

    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    m = sp.identity(4, format="csr")
    path = kept_module._path("weights", (np.ones(2),), (kept_module,))
    path.parent.mkdir(parents=True)
    np.savez(path, data=np.ones(4), indices=np.array([0, 9, 1, 2]), indptr=np.arange(5), shape=np.array([4, 4]))
    assert np.array_equal(kept_sparse("weights", (np.ones(2),), (kept_module,), lambda: m).toarray(), np.eye(4))
    # written anew: read back without deriving
    again = kept_sparse("weights", (np.ones(2),), (kept_module,), lambda: pytest.fail("derived again"))
    assert np.array_equal(again.toarray(), np.eye(4))
