"""Arrays and sparse matrices that slow rules derive from a head, kept in the user cache
(:func:`.asset.cache_dir`).

A result is named by a hash of everything it depends on: the input arrays and the source of the modules
whose rules derive it, so a calibrated or custom head, or a changed rule, gets its own file. Written
atomically (a torn or foreign file is derived again); where the cache cannot be written, every call derives.
Each kind keeps its :data:`KEEP` most recently used files (a head calibrated to every photo a user tries, and
every edit of a rule, would otherwise add files for good).
"""
from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path
from types import ModuleType

import numpy as np
import scipy.sparse as sp

KEEP = 64
"""Files kept per kind; the least recently used beyond these are removed when one is written."""
SPARSE = ("data", "indices", "indptr", "shape")
"""The arrays a sparse matrix is kept as (:func:`kept_sparse`)."""


def kept(kind: str, inputs: Iterable[np.ndarray | str | bytes], rules: Iterable[ModuleType],
         derive: Callable[[], np.ndarray]) -> np.ndarray:
    """``derive()``, or what it gave before for the same ``inputs`` and ``rules`` (read back from
    ``cache_dir()/kind/``)."""
    return _kept(kind, inputs, rules, ("array",), lambda: {"array": np.asarray(derive())})["array"]


def kept_sparse(kind: str, inputs: Iterable[np.ndarray | str | bytes], rules: Iterable[ModuleType],
                derive: Callable[[], sp.spmatrix]) -> sp.csr_matrix:
    """:func:`kept` of a sparse matrix (kept as its CSR arrays)."""
    a = _kept(kind, inputs, rules, SPARSE, lambda: _csr_arrays(derive()))
    try:
        m = sp.csr_matrix((a["data"], a["indices"], a["indptr"]), shape=tuple(int(n) for n in a["shape"]))
        m.check_format(full_check=True)
        return m
    except (ValueError, TypeError, IndexError):  # a foreign file's arrays that make no matrix: derived and written anew
        m = sp.csr_matrix(derive())
        _write(_path(kind, inputs, rules), _csr_arrays(m))
        return m


def _csr_arrays(matrix: sp.spmatrix) -> dict[str, np.ndarray]:
    m = sp.csr_matrix(matrix)
    return dict(zip(SPARSE, (m.data, m.indices, m.indptr, np.array(m.shape))))


def _kept(kind: str, inputs: Iterable[np.ndarray | str | bytes], rules: Iterable[ModuleType],
          names: tuple[str, ...], derive: Callable[[], dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """The arrays ``derive()`` gives by ``names``, or gave before (see :func:`kept`)."""
    path = _path(kind, inputs, rules)
    if path.is_file():
        try:
            with np.load(path, allow_pickle=False) as saved:
                arrays = {name: np.array(saved[name]) for name in names}
            _touch(path)
            return arrays
        except Exception:  # noqa: BLE001 - torn, foreign or unreadable (zlib, zip, npy, key errors alike)
            pass  # derived again below and written anew
    arrays = derive()
    _write(path, arrays)
    return arrays


def _write(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Write ``arrays`` at ``path`` atomically (a reader sees the old file or the new one), then prune its kind."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=".", suffix=".part", delete=False) as tmp:
            np.savez_compressed(tmp, **arrays)
        os.chmod(tmp.name, 0o644)  # a cache shared by users ($MPEG4FA_CACHE) is read by all
        os.replace(tmp.name, path)
        _prune(path.parent)
    except OSError:
        pass  # no writable cache: the next call derives again
    finally:
        if tmp is not None and os.path.exists(tmp.name):
            os.unlink(tmp.name)


def _touch(path: Path) -> None:
    try:
        os.utime(path)
    except OSError:
        pass  # read-only cache: the order of use is lost, nothing else


def _prune(folder: Path) -> None:
    """Remove all but the :data:`KEEP` most recently used files of a kind."""
    files = sorted(folder.glob("*.npz"), key=lambda p: p.stat().st_mtime_ns, reverse=True)
    for old in files[KEEP:]:
        try:
            old.unlink()
        except OSError:
            pass  # gone already (another process pruned it), or not ours to remove


def _path(kind: str, inputs: Iterable[np.ndarray | str | bytes], rules: Iterable[ModuleType]) -> Path:
    from mpeg4fa.face import asset
    h = hashlib.sha256()
    for module in rules:
        h.update(Path(module.__file__).read_bytes())
    for a in inputs:
        if isinstance(a, (str, bytes)):
            h.update(a.encode() if isinstance(a, str) else a)
            continue
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype}{a.shape}".encode())
        h.update(a.tobytes())
    return asset.cache_dir() / kind / f"{h.hexdigest()[:32]}.npz"
