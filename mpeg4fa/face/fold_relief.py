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


def skin_triangles(mesh) -> np.ndarray:
    """The skin triangles a fold counts on (:func:`.creases.measure_pose`): none inside the lip or lid loops."""
    from mpeg4fa.face.quality import skin_graph
    tris = np.asarray(mesh.triangles["skin"], dtype=np.int64)
    inside = np.zeros(mesh.n_vertices, bool)
    inside[skin_graph(mesh).inside] = True
    return tris[~inside[tris].any(axis=1)]


def even_out(rest: np.ndarray, triangles: np.ndarray, fields: list[np.ndarray],
             poses: Callable[[list[np.ndarray]], Iterable[np.ndarray]], held: list[np.ndarray]) -> list[np.ndarray]:
    """``fields`` (per vertex: scalars ``(V,)`` or vectors ``(V, 3)``) evened out until none of ``poses(fields)``
    (the posed vertices of each case) folds one of ``triangles`` (module docstring); ``held[k]``: vertices whose
    value in ``fields[k]`` stays."""
    fields = [np.array(f, dtype=np.float64, copy=True) for f in fields]
    limit = np.cos(np.radians(GUARD_DEGREES))
    n0_all = unit_normals(rest, triangles)
    for _ in range(MAX_ROUNDS):
        moving = np.zeros(len(rest), bool)
        for f in fields:
            moving |= (f != 0) if f.ndim == 1 else np.any(f != 0, axis=1)
        near = np.flatnonzero(moving[triangles].any(axis=1))
        tris, n0 = triangles[near], n0_all[near]
        a, b = triangle_pairs(tris)
        sheet = np.einsum("ij,ij->i", n0[a], n0[b]) > np.cos(np.radians(SAME_SHEET_DEGREES))
        a, b = a[sheet], b[sheet]
        hit = np.zeros(len(tris), bool)
        for posed in poses(fields):
            n1 = unit_normals(posed, tris)
            hit |= np.einsum("ij,ij->i", n0, n1) < limit
            apart = np.einsum("ij,ij->i", n1[a], n1[b]) < limit
            hit[a[apart]] = hit[b[apart]] = True
        if not hit.any():
            break
        t = tris[hit]
        for f, keep in zip(fields, held):
            values = f[t]  # (T, 3) or (T, 3, 3)
            pull = (values.mean(axis=1, keepdims=True) - values).reshape(len(t) * 3, *f.shape[1:])
            step = np.zeros_like(f)
            count = np.zeros(len(f))
            np.add.at(step, t.ravel(), pull)
            np.add.at(count, t.ravel(), 1.0)
            step /= np.maximum(count, 1.0).reshape(-1, *([1] * (f.ndim - 1)))
            step[keep] = 0.0
            f += 0.5 * step
            if f.ndim == 1:
                f[np.abs(f) < TINY] = 0.0
    return fields
