"""The neck's cut: its rim as one loop of skin vertices, and a cap of triangles that closes it.

The head ends in a planar cut across the neck (:data:`.asset.NECK_CUT_Y` on the generic head).
Seen from below, or from a three-quarter view a little below, an open cut shows the inside of
the head; the cap closes it with triangles over the rim's own vertices (no new vertices, so a
pose moves it with the rim, which only a deep bow moves: the neck's share of a head turn is 0 at
the cut, and a bow past :data:`.rig.THROAT_BOW_DEGREES` turns the whole neck by its excess). The
rim is triangulated by ear clipping in the cut's plane, so a rim that is not convex (the neck's
sides flare into the shoulders) is still covered exactly once.
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import adjacency

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


def neck_vertices(mesh: HeadMesh) -> np.ndarray:
    """The vertices that turn only partly with the head (:func:`.rig.head_weights`: the neck, from
    the cut up to where it meets the head), and the ring of skin joined to them (the triangles that
    bridge to the head). With the cap the neck is closed, so its back side never shows except as a
    silhouette sliver where a turn twists a row of its long triangles over the next (under the chin
    too, where the neck meets the head: a profile view turned 5 degrees showed one there)."""
    from mpeg4fa.face.rig import head_weights

    skin = mesh.part("skin")
    on = np.zeros(skin.stop - skin.start, bool)
    idx = head_weights(mesh)[0]
    on[idx[(idx >= skin.start) & (idx < skin.stop)] - skin.start] = True
    graph = adjacency(mesh.triangles["skin"] - skin.start, skin.stop - skin.start)
    ring = np.asarray(graph @ on.astype(np.float64)).ravel() > 0
    return np.flatnonzero(on | ring) + skin.start


RIM_HARMONICS = 5
"""The rim's outline keeps this many Fourier harmonics (round the loop) when it is smoothed."""
RIM_BLEND_MM = 20.0
"""How far up the neck the smoothed rim's change fades out."""


def smooth_rim(mesh: HeadMesh) -> HeadMesh:
    """The mesh with its cut's outline made smooth: the rim keeps the low harmonics of its outline
    in the cut's plane (the generic head's flares into the shoulders left notches at the sides, a
    jagged bottom edge from three-quarter views and fins that a head turn flipped), and the neck
    above follows the change, fading out over :data:`RIM_BLEND_MM`. Nothing else moves."""
    loop = rim_loop(mesh)
    if len(loop) < 2 * RIM_HARMONICS + 3:
        return mesh
    v = mesh.vertices.copy()
    outline = v[loop][:, [0, 2]]
    spectrum = np.fft.rfft(outline, axis=0)
    spectrum[RIM_HARMONICS + 1:] = 0.0
    smooth = np.fft.irfft(spectrum, n=len(loop), axis=0)
    delta = smooth - outline
    skin = mesh.part("skin")
    y = v[skin, 1]
    height = y - y.min()
    near = np.flatnonzero(height < RIM_BLEND_MM)
    d2 = ((v[skin][near][:, None, [0, 2]] - outline[None]) ** 2).sum(axis=2)
    w = 1.0 / np.maximum(d2, 1e-6) ** 2
    follow = (w @ delta) / w.sum(axis=1, keepdims=True)
    fade = 1.0 - np.clip(height[near] / RIM_BLEND_MM, 0.0, 1.0)
    fade = fade * fade * (3.0 - 2.0 * fade)
    rows = near + skin.start
    v[rows[:, None], [0, 2]] += fade[:, None] * follow
    v[loop[:, None], [0, 2]] = smooth
    moved = np.union1d(rows, loop)
    mirror = np.asarray(mesh.mirror)[moved]  # exactly mirror symmetric again (the FFT rounds)
    x = 0.5 * (v[moved, 0] - v[mirror, 0])
    z = 0.5 * (v[moved, 2] + v[mirror, 2])
    v[moved, 0], v[moved, 2] = x, z
    v[mirror, 0], v[mirror, 2] = -x, z
    return mesh.with_vertices(v)
