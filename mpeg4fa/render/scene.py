"""The head as GL geometry: which mesh vertex feeds each GL vertex, and per-frame normals.

A mesh vertex on a texture seam has several UVs; GL needs one vertex per
(position, UV) pair. The layout is computed once per mesh, so each frame only
gathers positions and normals through one index array.

The neck's cut is closed by a cap (:func:`mpeg4fa.face.neck.cap_triangles`: triangles over the
rim's own vertices), drawn as skin with GL vertices of its own whose normal is the cap's, not
the rim's: the neck's side keeps its shading to the edge, and from below the head is a closed
bust, never its inside. So a back face of the neck (:func:`mpeg4fa.face.neck.neck_vertices`) that
shows is a sliver at its silhouette, where a head turn twists one row of its long triangles over
the next (a pixel at a time, at any turn): it is drawn as the skin it is, not as the inside.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import sparse

from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.neck import cap_triangles, neck_vertices
from mpeg4fa.render.details import (brow_coordinates, cavity_weights, nose_coordinates, tongue_coordinates,
                                    tooth_coordinates)
from mpeg4fa.render.materials import LIP_OUTLINE, PART_MATERIAL, lip_weights


CAP_INSET_MM = 0.0
"""The neck cap sits this far inside the rim (too little to see from below)."""


@dataclass(frozen=True)
class SceneLayout:
    source: np.ndarray     # (N,) mesh vertex index of each GL vertex
    uv: np.ndarray         # (N, 2) float32
    material: np.ndarray   # (N,) float32 material slot
    lips: np.ndarray       # (N,) float32 0..1, how much of the lip colour the untextured skin takes
    cavity: np.ndarray     # (N,) float32 0..1, how deep in the mouth (dark) a skin vertex is
    detail: np.ndarray     # (N, 2) float32: brow coordinates on the skin, tooth coordinates on the teeth
    nose: np.ndarray       # (N, 2) float32: nose wrinkle window and coordinate on the skin (0 elsewhere)
    neck: np.ndarray       # (N,) float32: 1 on the neck's skin and cap (its back side is drawn as skin), else 0
    indices: np.ndarray    # (T, 3) uint32 GL vertex indices, all drawn parts
    triangles: np.ndarray  # (T, 3) mesh vertex indices (for normals; the cap's are not among them)
    incidence: sparse.csr_matrix  # (V, T): sums face normals onto vertices
    cap: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64))  # (K, 3) mesh vertex indices of the neck cap
    cap_vertices: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))  # GL vertices of the cap (their normal is the cap's)

    @property
    def n_vertices(self) -> int:
        return len(self.source)


def build_layout(mesh: HeadMesh) -> SceneLayout:
    """One GL vertex per distinct (mesh vertex, UV) among the drawn parts' triangle corners."""
    tris, uvs, mats = [], [], []
    for part, slot in PART_MATERIAL.items():
        t = mesh.triangles.get(part)
        if t is None or not len(t):
            continue
        tris.append(np.asarray(t, np.int64))
        uvs.append(np.asarray(mesh.corner_uvs[part], np.float64))
        mats.append(np.full(len(t), slot))
    tri = np.concatenate(tris)
    cap = cap_triangles(mesh) if "skin" in mesh.triangles else np.zeros((0, 3), np.int64)
    if len(cap):  # the rim's corner UVs, from any skin triangle that has the vertex
        skin_tri = np.asarray(mesh.triangles["skin"], np.int64).reshape(-1)
        uv_of = dict(zip(skin_tri.tolist(), np.asarray(mesh.corner_uvs["skin"], np.float64).reshape(-1, 2)))
        uvs.append(np.array([uv_of[int(v)] for v in cap.reshape(-1)]).reshape(len(cap), 3, 2))
        mats.append(np.full(len(cap), PART_MATERIAL["skin"]))
    drawn = np.concatenate([tri, cap])
    corner_uv = np.concatenate(uvs).reshape(-1, 2)
    corner_mat = np.repeat(np.concatenate(mats), 3)
    on_cap = np.r_[np.zeros(tri.size, np.int64), np.ones(cap.size, np.int64)]
    keys = np.c_[drawn.reshape(-1), np.round(corner_uv * 2**20), on_cap].astype(np.int64)
    unique, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    source = unique[:, 0].astype(np.int64)
    inverse = inverse.reshape(-1)
    lips = np.zeros(len(source), np.float32)
    skin = corner_mat[first] == PART_MATERIAL["skin"]
    if all(label in mesh.fp_labels for label in LIP_OUTLINE):
        outline = np.array([mesh.fp(label) for label in LIP_OUTLINE])
        lips[skin] = lip_weights(mesh.vertices[source[skin]], outline)
    detail = np.zeros((len(source), 2), np.float32)
    detail[skin] = brow_coordinates(mesh, mesh.vertices[source[skin]])
    nose = np.zeros((len(source), 2), np.float32)
    nose[skin] = nose_coordinates(mesh, mesh.vertices[source[skin]])
    neck = np.zeros(len(source), np.float32)
    if len(cap):  # only a capped neck is closed: an open cut shows its true inside
        on_neck = np.zeros(mesh.n_vertices, bool)
        on_neck[neck_vertices(mesh)] = True
        neck[skin] = on_neck[source[skin]]
    for part in ("teeth_upper", "teeth_lower"):
        if part in mesh.part_ranges and len(mesh.triangles.get(part, ())):
            a, b = mesh.part_ranges[part]
            arch = tooth_coordinates(mesh.vertices[a:b], upper=part == "teeth_upper")
            mine = (source >= a) & (source < b)
            detail[mine] = arch[source[mine] - a]
    if "tongue" in mesh.part_ranges and len(mesh.triangles.get("tongue", ())):
        a, b = mesh.part_ranges["tongue"]
        mine = (source >= a) & (source < b)
        detail[mine] = tongue_coordinates(mesh.vertices[a:b])[source[mine] - a]
    return SceneLayout(
        source=source,
        uv=corner_uv[first].astype(np.float32),
        material=corner_mat[first].astype(np.float32),
        lips=lips,
        cavity=cavity_weights(mesh)[source].astype(np.float32),
        detail=detail,
        nose=nose,
        neck=neck,
        indices=inverse.reshape(-1, 3).astype(np.uint32),
        triangles=tri,
        incidence=incidence_matrix(tri, mesh.n_vertices),
        cap=cap,
        cap_vertices=np.flatnonzero(unique[:, -1] == 1),
    )


def incidence_matrix(triangles: np.ndarray, n_vertices: int) -> sparse.csr_matrix:
    """(V, T) ones where a vertex is a corner of a triangle: sums per-triangle values onto vertices."""
    n_tri = len(triangles)
    return sparse.csr_matrix((np.ones(3 * n_tri), (triangles.reshape(-1), np.repeat(np.arange(n_tri), 3))),
                             shape=(n_vertices, n_tri))


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray,
                   incidence: sparse.csr_matrix | None = None) -> np.ndarray:
    """Area-weighted unit vertex normals (V, 3) from the given triangles (zero where a vertex has none).

    Pass ``incidence`` (:func:`incidence_matrix`) when the triangles are used for many frames.
    """
    v = vertices[triangles]
    face = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    if incidence is None:
        incidence = incidence_matrix(triangles, len(vertices))
    normals = incidence @ face
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.where(length > 0, length, 1.0)


def vertex_data(layout: SceneLayout, vertices: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Interleaved position + normal per GL vertex, (N, 6) float32, written into ``out`` if given."""
    if out is None:
        out = np.empty((layout.n_vertices, 6), np.float32)
    normals = vertex_normals(vertices, layout.triangles, layout.incidence)
    out[:, :3] = vertices[layout.source]
    out[:, 3:] = normals[layout.source]
    if len(layout.cap):  # the cap is flat: one normal, its area-weighted mean
        p = vertices[layout.cap]
        n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]).sum(axis=0)
        n /= max(float(np.linalg.norm(n)), 1e-12)
        out[layout.cap_vertices, 3:] = n
        # set in by CAP_INSET, so that from above its back never shows along the rim (depth ties)
        out[layout.cap_vertices, :3] -= CAP_INSET_MM * n
    return out
