"""The lips drawn finer than their mesh: each triangle split into a grid, its points set on the smooth surface its
corners' normals describe (Phong tessellation), every frame.

The generic head's lip triangles have edges of 2.4 mm (median; 5.6 at the 90th percentile), so close up the
lips' outlines and the mouth's opening showed as polylines. Smooth normals shade a surface round but leave its
outline straight; only more points on it bend the outline. Each triangle of the patch (:func:`mouth_patch`) is cut
into ``LEVEL`` x ``LEVEL`` triangles; a point of it goes from its place on the flat triangle toward the mean of its
projections onto the tangent planes at the corners (each weighted as the point is by its corners), by a share that
is :data:`SHARE` inside the patch and 0 at its edge, so that the patch's outer edges stay straight: no point is put
on them (a T-junction with the skin beside it, where the rasteriser left pinholes), and they meet that skin without
a crack. A point on an edge depends on that edge's two corners alone, so neighbours agree on it. Drawn by the
renderer in place of the patch's own triangles (the UV bake keeps those); the GLB and the browser pages draw the
mesh as it is. Across the mesh's own edges the finer triangles turn 0.69-0.73 of what the same cut left flat does
(median; neutral, AA, PP, joy, surprise: ``tests/render/test_refine.py``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from mpeg4fa.render.scene import SceneLayout

LEVEL = 2
"""Each patch triangle's edges are cut into this many (a triangle into its square: 4; at 3, 9, the outline rounder
still but render + readback 1.21 x, llvmpipe paying by the triangle)."""
SHARE = 0.75
"""How far a point goes from the flat triangle to the curved surface (Phong tessellation's usual 3/4)."""
LIP = 0.3
"""The patch: skin triangles with a corner taking more than this of the lip colour (``layout.lips``): the lips, whose
outline and opening show the mesh's steps."""
DEEP = 0.7
"""Nor a triangle with a corner deeper in the mouth's dark than this (``layout.cavity``): the lips' far inside, which
an open mouth barely shows (llvmpipe pays for every triangle drawn: 596 triangles, against 762 with it; at 0.5 and
0.6 a pixel of the skin's back showed where the patch ended inside the lower lip, AA at three-quarter)."""


@dataclass(frozen=True)
class Patch:
    """The finer mesh of a patch: the edges whose corners' tangent planes bend it, one sparse operator from the GL
    vertices and those edges' projections to the points (positions) and one from the GL vertices (normals), the finer
    triangles, and per point its owner triangle's GL vertices and weights (for the static attributes)."""

    edges: np.ndarray      # (E, 2) GL vertex indices, the lower first
    positions: sp.csr_matrix  # (K, N + 2E): points from [GL vertices; pi_a(p_b) per edge; pi_b(p_a) per edge]
    normals: sp.csr_matrix    # (K, N): points' normals (to be normalised) from the GL vertices' normals
    indices: np.ndarray    # (S, 3) uint32 point indices
    parents: np.ndarray    # (S,) which of the patch's triangles each finer one is cut from
    corners: np.ndarray    # (K, 3) GL vertex indices of each point's owner triangle
    weights: np.ndarray    # (K, 3) its barycentric weights there
    triangles: np.ndarray  # (P,) the patch's triangles (rows of the layout's indices)

    @property
    def n_points(self) -> int:
        return len(self.corners)


def mouth_patch(layout: SceneLayout, skin_rows: np.ndarray) -> np.ndarray:
    """Rows of ``layout.indices`` (among ``skin_rows``) that :func:`refine` draws finer: the lips (a corner taking more
    than :data:`LIP` of the lip colour), but for their far inside (:data:`DEEP`)."""
    rows = np.asarray(skin_rows, np.int64)
    corners = layout.indices[rows]
    lips = layout.lips[corners].max(axis=1) > LIP
    seen = layout.cavity[corners].max(axis=1) <= DEEP
    return rows[lips & seen]


def refine(layout: SceneLayout, rows: np.ndarray) -> Patch:
    """The finer mesh of the triangles ``rows`` of ``layout.indices`` (module docstring)."""
    tris = np.asarray(layout.indices[rows], np.int64)
    # corners on the patch's edge (used by a skin triangle outside it, by mesh vertex) keep their flat place
    inside = np.zeros(len(layout.indices), bool)
    inside[rows] = True
    source = layout.source
    outside_vertices = np.unique(source[layout.indices[~inside & (layout.material[layout.indices[:, 0]] == 0)]])
    share = np.where(np.isin(source, outside_vertices), 0.0, SHARE)
    n = LEVEL
    grid = [(i, j) for i in range(n + 1) for j in range(n + 1 - i)]  # (i, j): weights ((n-i-j), i, j) / n
    keys: dict[tuple, int] = {}
    corners, weights, point_of = [], [], np.zeros((len(tris), len(grid)), np.int64)
    for t, (a, b, c) in enumerate(tris):
        for g, (i, j) in enumerate(grid):
            w = np.array([n - i - j, i, j], float) / n
            on = sorted((int(v), x) for v, x in zip((a, b, c), w) if x > 0)
            if len(on) == 1:
                key = ("v", on[0][0])
            elif len(on) == 2 and not (share[on[0][0]] or share[on[1][0]]):
                # on an edge whose corners keep their flat place (the patch's outline): at its nearer corner, so that
                # the edge stays one edge, as the skin beside it has it (a point on it would be a T-junction, and
                # the rasteriser left pinholes along such edges)
                key = ("v", on[0][0] if on[0][1] > on[1][1] else on[1][0])
                w = np.array([float(v == key[1]) for v in (a, b, c)])
            elif len(on) == 2:  # an edge point: by its two GL vertices and its place between them
                key = ("e", on[0][0], on[1][0], int(round(on[1][1] * n)))
            else:
                key = ("t", t, i, j)
            k = keys.get(key)
            if k is None:
                k = keys[key] = len(corners)
                corners.append((a, b, c))
                weights.append(w)
            point_of[t, g] = k
    index_of = {ij: g for g, ij in enumerate(grid)}
    subs, parents = [], []
    for t in range(len(tris)):
        for i in range(n):
            for j in range(n - i):
                subs.append((point_of[t, index_of[i, j]], point_of[t, index_of[i + 1, j]],
                             point_of[t, index_of[i, j + 1]]))
                parents.append(t)
                if i + j < n - 1:
                    subs.append((point_of[t, index_of[i + 1, j]], point_of[t, index_of[i + 1, j + 1]],
                                 point_of[t, index_of[i, j + 1]]))
                    parents.append(t)
    kept = [k for k, sub in enumerate(subs) if len(set(sub)) == 3]  # not those the outline's edges collapsed
    subs, parents = [subs[k] for k in kept], np.asarray(parents, np.int64)[kept]
    corners, weights = np.array(corners, np.int64).reshape(-1, 3), np.array(weights).reshape(-1, 3)
    return _operators(len(source), corners, weights, share, np.array(subs, np.uint32).reshape(-1, 3), parents,
                      np.asarray(rows, np.int64))


def _operators(n_gl: int, corners: np.ndarray, weights: np.ndarray, share: np.ndarray, subs: np.ndarray,
               parents: np.ndarray, rows: np.ndarray) -> Patch:
    """Phong tessellation as sparse operators: a point is sum_i w_i^2 p_i + sum_{i<j} w_i w_j (pi_i(p_j) + pi_j(p_i))
    on the curved surface (pi_i: the projection onto corner i's tangent plane), sum_i w_i p_i on the flat triangle,
    and goes between them by its share."""
    pairs = np.sort(np.stack([corners[:, [0, 1]], corners[:, [1, 2]], corners[:, [2, 0]]], axis=1), axis=2)
    edges, edge_of = np.unique(pairs.reshape(-1, 2), axis=0, return_inverse=True)
    edge_of = edge_of.reshape(-1, 3)
    k = len(corners)
    alpha = (weights * share[corners]).sum(axis=1)
    rows_, cols_, vals_ = [], [], []
    for c in range(3):  # the corners: (1 - alpha) w_i on the flat triangle, alpha w_i^2 on the curved one
        rows_.append(np.arange(k))
        cols_.append(corners[:, c])
        vals_.append((1.0 - alpha) * weights[:, c] + alpha * weights[:, c] ** 2)
    n_edges = len(edges)
    for c, (i, j) in enumerate(((0, 1), (1, 2), (2, 0))):
        both = alpha * weights[:, i] * weights[:, j]
        e = edge_of[:, c]
        for offset in (n_gl, n_gl + n_edges):  # pi_lo(p_hi) and pi_hi(p_lo) of that edge
            rows_.append(np.arange(k))
            cols_.append(offset + e)
            vals_.append(both)
    positions = sp.csr_matrix((np.concatenate(vals_), (np.concatenate(rows_), np.concatenate(cols_))),
                              shape=(k, n_gl + 2 * n_edges))
    normals = sp.csr_matrix((weights.ravel(), (np.repeat(np.arange(k), 3), corners.ravel())), shape=(k, n_gl))
    positions.eliminate_zeros()
    return Patch(edges=edges, positions=positions, normals=normals, indices=subs, parents=parents, corners=corners,
                 weights=weights, triangles=rows)


def interpolated(patch: Patch, columns: np.ndarray) -> np.ndarray:
    """A per-GL-vertex attribute ``(N, ...)`` at the patch's points (linearly, as the rasteriser would)."""
    values = np.asarray(columns)[patch.corners]  # (K, 3, ...)
    w = patch.weights.reshape(patch.weights.shape + (1,) * (values.ndim - 2))
    return (values * w).sum(axis=1)


def refined_vertices(patch: Patch, data: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(K, 6) float32 position + normal of the patch's points from the GL vertices' ``data`` (N, 6) of this frame."""
    lo, hi = data[patch.edges[:, 0]], data[patch.edges[:, 1]]
    p_lo, n_lo, p_hi, n_hi = lo[:, :3], lo[:, 3:], hi[:, :3], hi[:, 3:]
    onto_lo = p_hi - ((p_hi - p_lo) * n_lo).sum(axis=1, keepdims=True) * n_lo  # pi_lo(p_hi)
    onto_hi = p_lo - ((p_lo - p_hi) * n_hi).sum(axis=1, keepdims=True) * n_hi  # pi_hi(p_lo)
    if out is None:
        out = np.empty((patch.n_points, 6), np.float32)
    out[:, :3] = patch.positions @ np.concatenate([data[:, :3], onto_lo, onto_hi])
    normal = patch.normals @ data[:, 3:]
    out[:, 3:] = normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
    return out
