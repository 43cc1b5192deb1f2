"""Evening out a motion field where the poses it makes would fold the skin (one rule for lids and face units).

A triangle whose three vertices move alike (one angle about a lid's axis, one displacement of a face unit)
moves rigidly and cannot fold. So where a pose turns a skin triangle by more than :data:`GUARD_DEGREES`
from rest, or turns two neighbours that were one smooth sheet (:data:`SAME_SHEET_DEGREES`) that far
apart, each of its vertices' values moves halfway to the triangle's mean, round after round, until no
pose does. Held vertices (feature points, whose motion the standard fixes) keep theirs; the field may
spread to vertices that did not move before. Used by :mod:`.lid_folds` (the lids' angle shares at the
eye corners), :mod:`.rig` (the cheek points' skin weights, :data:`.rig.RELIEVED`) and :mod:`.deformers.arkit`
(sculpted face units that fold at full weight).
"""
from __future__ import annotations

import hashlib
from collections.abc import Callable, Iterable

import numpy as np

from mpeg4fa.face.regions import triangle_pairs, unit_normals

GUARD_DEGREES = 78.0
"""A triangle turned by more than this (or a pair of neighbours this far from facing one way) is evened out:
some room below the 90 degrees that count as a fold (:mod:`.creases`)."""
SAME_SHEET_DEGREES = 60.0
"""Neighbours this close at rest are one smooth sheet (as :data:`.creases.SAME_SIDE_DEGREES`)."""
MAX_ROUNDS = 200
"""Rounds at most (where held vertices leave folds that evening out cannot remove, it stops there)."""
TINY = 1e-4
"""A scalar share below this is none (the field's support stays where it matters)."""


_SKIN_TRIANGLES: dict[bytes, np.ndarray] = {}
""":func:`skin_triangles` per head (a digest of its shape, skin and feature points): the rig asks three times."""


def skin_triangles(mesh) -> np.ndarray:
    """The skin triangles a fold counts on (:func:`.creases.measure_pose`): none inside the lip or lid loops."""
    from mpeg4fa.face.quality import skin_graph
    tris = np.asarray(mesh.triangles["skin"], dtype=np.int64)
    h = hashlib.sha256()
    for a in (np.asarray(mesh.vertices, np.float64), tris, np.asarray(mesh.fp_vertex, np.int64)):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(repr((tuple(mesh.fp_labels), tuple(mesh.part_ranges["skin"]))).encode())
    key = h.digest()
    if key not in _SKIN_TRIANGLES:
        inside = np.zeros(mesh.n_vertices, bool)
        inside[skin_graph(mesh).inside] = True
        if len(_SKIN_TRIANGLES) >= 8:
            _SKIN_TRIANGLES.pop(next(iter(_SKIN_TRIANGLES)))
        _SKIN_TRIANGLES[key] = tris[~inside[tris].any(axis=1)]
    return _SKIN_TRIANGLES[key].copy()


def _stacked_normals(stack: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """``(C, T, 3)`` unit normals of ``tris`` in each of ``C`` posed copies ``(C, V, 3)`` (:func:`.regions.unit_normals`
    over the copies laid end to end, one call a round)."""
    c, v = stack.shape[:2]
    offset = (np.arange(c, dtype=np.int64) * v)[:, None, None]
    return unit_normals(stack.reshape(c * v, 3), (tris[None] + offset).reshape(-1, 3)).reshape(c, len(tris), 3)


def even_out(rest: np.ndarray, triangles: np.ndarray, fields: list[np.ndarray],
             poses: Callable[[list[np.ndarray]], Iterable[np.ndarray] | np.ndarray],
             held: list[np.ndarray]) -> list[np.ndarray]:
    """``fields`` (per vertex: scalars ``(V,)`` or vectors ``(V, 3)``) evened out until none of ``poses(fields)``
    (the posed vertices of each case, or all cases stacked ``(C, V, 3)``) folds one of ``triangles`` (module
    docstring); ``held[k]``: vertices whose value in ``fields[k]`` stays. Vectorised over the cases and the
    triangles (a lid's 200 rounds of 12 cases cost what one case did a round)."""
    fields = [np.array(f, dtype=np.float64, copy=True) for f in fields]
    triangles = np.asarray(triangles, dtype=np.int64)
    n = len(rest)
    limit = np.cos(np.radians(GUARD_DEGREES))
    n0_all = unit_normals(rest, triangles)
    a_all, b_all = triangle_pairs(triangles)
    sheet = np.einsum("ij,ij->i", n0_all[a_all], n0_all[b_all]) > np.cos(np.radians(SAME_SHEET_DEGREES))
    a_all, b_all = a_all[sheet], b_all[sheet]
    for _ in range(MAX_ROUNDS):
        moving = np.zeros(n, bool)
        for f in fields:
            moving |= (f != 0) if f.ndim == 1 else np.any(f != 0, axis=1)
        near_mask = moving[triangles].any(axis=1)
        near = np.flatnonzero(near_mask)
        tris, n0 = triangles[near], n0_all[near]
        local = np.full(len(triangles), -1, np.int64)
        local[near] = np.arange(len(near))
        both = near_mask[a_all] & near_mask[b_all]
        a, b = local[a_all[both]], local[b_all[both]]
        posed = poses(fields)
        stack = posed if isinstance(posed, np.ndarray) and posed.ndim == 3 else np.stack(list(posed))
        n1 = _stacked_normals(stack, tris)
        hit = (np.einsum("cij,ij->ci", n1, n0) < limit).any(axis=0)
        apart = (np.einsum("cij,cij->ci", n1[:, a], n1[:, b]) < limit).any(axis=0)
        hit[a[apart]] = hit[b[apart]] = True
        if not hit.any():
            break
        t = tris[hit]
        count = np.bincount(t.ravel(), minlength=n).astype(np.float64)
        for f, keep in zip(fields, held):
            values = f[t]  # (T, 3) or (T, 3, 3)
            pull = (values.mean(axis=1, keepdims=True) - values).reshape(len(t) * 3, -1)
            step = np.stack([np.bincount(t.ravel(), pull[:, k], minlength=n) for k in range(pull.shape[1])], axis=1)
            step /= np.maximum(count, 1.0)[:, None]
            step[keep] = 0.0
            f += 0.5 * step.reshape(f.shape)
            if f.ndim == 1:
                f[np.abs(f) < TINY] = 0.0
    return fields
