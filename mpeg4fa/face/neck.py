"""The neck's cut: its rim as one loop of skin vertices, and a cap of triangles that closes it.

The head ends in a planar cut across the neck (:data:`.asset.NECK_CUT_Y` on the generic head).
Seen from below, or from a three-quarter view a little below, an open cut shows the inside of
the head; the cap closes it with triangles over the rim's own vertices (no new vertices, so a
pose moves it with the rim, which nothing but the neck's share of a head turn moves: that share
is 0 at the cut). The rim is triangulated by ear clipping in the cut's plane, so a rim that is
not convex (the neck's sides flare into the shoulders) is still covered exactly once.
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.face.mesh import HeadMesh

RIM_BAND_MM = 0.5
"""Border vertices within this of the skin's lowest point are on the cut."""


def _border_edges(triangles: np.ndarray) -> np.ndarray:
    """Edges that belong to one triangle only (the mesh's open borders), as (a, b) in winding order."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return edges[counts[inverse.ravel()] == 1]


def rim_loop(mesh: HeadMesh) -> np.ndarray:
    """The cut's border vertices in order round the loop (empty when the skin has no such border)."""
    skin = mesh.part("skin")
    y = mesh.vertices[:, 1]
    bottom = y[skin].min()
    border = _border_edges(np.asarray(mesh.triangles["skin"], np.int64))
    low = (y[border[:, 0]] < bottom + RIM_BAND_MM) & (y[border[:, 1]] < bottom + RIM_BAND_MM)
    border = border[low]
    if len(border) < 3:
        return np.zeros(0, np.int64)
    following = {int(a): int(b) for a, b in border}
    start = int(border[0, 0])
    loop, v = [start], following.get(start)
    while v is not None and v != start and len(loop) <= len(border):
        loop.append(v)
        v = following.get(v)
    return np.asarray(loop if v == start else [], np.int64)


def _ear_clip(points: np.ndarray) -> list[tuple[int, int, int]]:
    """Triangles (indices into ``points``, (n, 2), a simple polygon) covering it once."""
    area = 0.5 * np.sum(points[:, 0] * np.roll(points[:, 1], -1) - np.roll(points[:, 0], -1) * points[:, 1])
    order = list(range(len(points))) if area > 0 else list(range(len(points)))[::-1]

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    out = []
    guard = 0
    while len(order) > 3 and guard < 10 * len(points) ** 2:
        guard += 1
        n = len(order)
        best = None
        for k in range(n):
            i, j, m = order[k - 1], order[k], order[(k + 1) % n]
            a, b, c = points[i], points[j], points[m]
            if cross(a, b, c) <= 1e-12:
                continue  # reflex or flat corner
            others = [points[q] for q in order if q not in (i, j, m)]
            if any(cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0 for p in others):
                continue
            # prefer the best-shaped ear (no slivers fanned from one corner)
            shape = cross(a, b, c) / max(np.sum((b - a) ** 2) + np.sum((c - b) ** 2) + np.sum((a - c) ** 2), 1e-12)
            if best is None or shape > best[0]:
                best = (shape, k)
        if best is None:
            break
        k = best[1]
        out.append((order[k - 1], order[k], order[(k + 1) % n]))
        del order[k]
    if len(order) == 3:
        out.append(tuple(order))
    return out


def cap_triangles(mesh: HeadMesh) -> np.ndarray:
    """``(K, 3)`` mesh vertex indices closing the neck's cut, facing down (out of the head)."""
    loop = rim_loop(mesh)
    if len(loop) < 3:
        return np.zeros((0, 3), np.int64)
    flat = mesh.vertices[loop][:, [2, 0]]  # (z, x): seen from below, counter-clockwise is +y... fixed below
    tris = np.asarray([[loop[i] for i in t] for t in _ear_clip(flat)], np.int64)
    p = mesh.vertices[tris]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    flip = normal[:, 1] > 0  # the cap faces down, out of the head
    tris[flip] = tris[flip][:, ::-1]
    return tris
