"""Fine creases of the rest skin, flattened on loading (issue 29 item 3).

The generic head has a few clusters of sub-millimetre triangles (the outer eye corners, the lip
corners) whose neighbours already meet at 45-60 degrees at rest. Every smooth weight still varies
across them, so a large move (the outer brow 4.5/4.6 lifted 26 mm, brows raised twice their
extreme) shears such a cluster by a fair share of its size: at the outer eye corner two
0.2 mm^2 triangles turned from 49 to 113 degrees apart, a fold line no weight or guard removes
(the guard at its full share left 98). Flattening the crease a little at rest (the vertices of
those pairs drawn toward their neighbours, :data:`STEPS` half-way umbrella steps: 8 vertices, at
most 0.43 mm) leaves them 11 degrees apart at rest and 20 at that raise. Feature points, the lip and
lid loops and all they enclose stay, and so does a cluster the step would sharpen (the lip
corners'); the result is mirror symmetric like the head. Since a raise holds the upper lids' front
edges (:func:`.lids.lid_strips`), that raise no longer folds the unflattened head either; the flattening
still takes 3 fold lines of 17 out of a cheek lifted to 600.
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import adjacency, triangle_pairs, unit_normals

TINY_MM2 = 0.3
"""Both triangles of a pair this small or smaller (mm^2; the skin's median is 6.6) ..."""
CREASE_DEGREES = (45.0, 60.0)
"""... meeting at an angle in this range at rest (a sharper edge is a real one, e.g. the nostril's;
the crease measure, :data:`.creases.SAME_SIDE_DEGREES`, counts pairs under 60 as one sheet)."""
STEPS = 2
"""Half-way umbrella steps (each vertex toward the mean of its neighbours)."""


def _creased_pairs(mesh: HeadMesh) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray]]:
    """The tiny triangle pairs creased at rest where none touches a feature point or the lip and lid
    loops (or what they enclose): ``(pairs, 6)`` vertex indices, and the two triangles ``(pairs, 3)`` each."""
    from mpeg4fa.face.quality import skin_graph  # the crease measure's own lip and lid loops

    tris = np.asarray(mesh.triangles["skin"], dtype=np.int64)
    a, b = triangle_pairs(tris)
    angle = _angles(mesh.vertices, tris, a, b)
    p = mesh.vertices[tris]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    low, high = CREASE_DEGREES
    pick = (angle > low) & (angle < high) & (np.maximum(area[a], area[b]) <= TINY_MM2)
    graph = skin_graph(mesh)
    held = np.zeros(mesh.n_vertices, bool)
    held[np.concatenate([mesh.fp_vertex, graph.inside, *graph.loops])] = True
    pick &= ~(held[tris[a]].any(axis=1) | held[tris[b]].any(axis=1))
    return np.concatenate([tris[a[pick]], tris[b[pick]]], axis=1), (tris[a[pick]], tris[b[pick]])


def _angles(v: np.ndarray, tris: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Degrees between the normals of triangles ``a`` and ``b`` (indices into ``tris``)."""
    n = unit_normals(v, tris)
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", n[a], n[b]), -1.0, 1.0)))


def _flattened(mesh: HeadMesh, rows: np.ndarray) -> np.ndarray:
    """Vertices with ``rows`` drawn toward their neighbours (:data:`STEPS`), mirror symmetric again."""
    v = mesh.vertices.copy()
    near = adjacency(mesh.triangles["skin"], mesh.n_vertices)[rows]
    count = np.asarray(near.sum(axis=1)).ravel()[:, None]
    for _ in range(STEPS):
        v[rows] = 0.5 * v[rows] + 0.5 * (near @ v) / count
    both = np.union1d(rows, np.asarray(mesh.mirror)[rows])  # exactly mirror symmetric (the steps round)
    m = np.asarray(mesh.mirror)[both]
    x, yz = 0.5 * (v[both, 0] - v[m, 0]), 0.5 * (v[both, 1:] + v[m, 1:])
    v[both, 0], v[both, 1:] = x, yz
    return v


def fine_crease_vertices(mesh: HeadMesh) -> np.ndarray:
    """Skin vertices of the tiny pairs creased at rest that drawing in opens: none touches a feature
    point or the lip and lid loops (or what they enclose), and a cluster that the step would sharpen
    instead (one at each lip corner went from 52 to 60 degrees) is left as it is."""
    quads, (ta, tb) = _creased_pairs(mesh)
    if not len(quads):
        return np.zeros(0, np.int64)
    tris = np.concatenate([ta, tb])
    a, b = np.arange(len(ta)), np.arange(len(ta), 2 * len(ta))
    before = _angles(mesh.vertices, tris, a, b)
    after = _angles(_flattened(mesh, np.unique(quads)), tris, a, b)
    worse = np.unique(quads[after >= before])
    return np.unique(quads[~np.isin(quads, worse).any(axis=1)])


def flatten_fine_creases(mesh: HeadMesh) -> HeadMesh:
    """The mesh with :func:`fine_crease_vertices` drawn toward their neighbours; nothing else moves."""
    rows = fine_crease_vertices(mesh)
    return mesh.with_vertices(_flattened(mesh, rows)) if len(rows) else mesh
