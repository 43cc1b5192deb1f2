"""Checked point arrays: the one gate every geometric function of the face layer goes through."""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from mpeg4fa.face.errors import FaceError


def as_points(array, name: str, where: str) -> np.ndarray:
    """``array`` as a finite ``(n, 3)`` float array, or a FaceError naming ``name`` and the first bad row."""
    try:
        pts = np.asarray(array, dtype=float)
    except (TypeError, ValueError) as exc:
        raise FaceError(f"{name} must be an array of 3D points: {exc}", where=where) from None
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise FaceError(f"{name} must have shape (n, 3), not {pts.shape}", where=where)
    bad = ~np.isfinite(pts).all(axis=1)
    if bad.any():
        raise FaceError(
            f"{name} has {int(bad.sum())} non-finite point(s), first at index {int(np.flatnonzero(bad)[0])}",
            where=where,
        )
    return pts


def reject_duplicates(pts: np.ndarray, tol: float, name: str, where: str, hint: str) -> None:
    """FaceError naming the first pairs of ``pts`` closer than ``tol`` (coincident controls make
    interpolation ill-posed)."""
    pairs = sorted(cKDTree(pts).query_pairs(tol))
    if pairs:
        shown = ", ".join(f"{a} and {b}" for a, b in pairs[:5])
        more = f" (and {len(pairs) - 5} more pairs)" if len(pairs) > 5 else ""
        raise FaceError(f"{len(pairs)} pair(s) of {name} coincide within {tol:g}: {shown}{more}",
                        where=where, hint=hint)
