"""The head as GL geometry: which mesh vertex feeds each GL vertex, and per-frame normals.

A mesh vertex on a texture seam has several UVs; GL needs one vertex per
(position, UV) pair. The layout is computed once per mesh, so each frame only
gathers positions and normals through one index array.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse

from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.render.details import brow_coordinates, cavity_weights, nose_coordinates, tooth_coordinates
from mpeg4fa.render.materials import LIP_OUTLINE, PART_MATERIAL, lip_weights


@dataclass(frozen=True)
class SceneLayout:
    source: np.ndarray     # (N,) mesh vertex index of each GL vertex
    uv: np.ndarray         # (N, 2) float32
    material: np.ndarray   # (N,) float32 material slot
    lips: np.ndarray       # (N,) float32 0..1, how much of the lip colour the untextured skin takes
    cavity: np.ndarray     # (N,) float32 0..1, how deep in the mouth (dark) a skin vertex is
    detail: np.ndarray     # (N, 2) float32: brow coordinates on the skin, tooth coordinates on the teeth
    nose: np.ndarray       # (N, 2) float32: nose wrinkle window and coordinate on the skin (0 elsewhere)
    indices: np.ndarray    # (T, 3) uint32 GL vertex indices, all drawn parts
    triangles: np.ndarray  # (T, 3) mesh vertex indices (for normals)
    incidence: sparse.csr_matrix  # (V, T): sums face normals onto vertices

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
    corner_uv = np.concatenate(uvs).reshape(-1, 2)
    corner_mat = np.repeat(np.concatenate(mats), 3)
    keys = np.c_[tri.reshape(-1), np.round(corner_uv * 2**20)].astype(np.int64)
    unique, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    source = unique[:, 0].astype(np.int64)
    lips = np.zeros(len(source), np.float32)
    skin = corner_mat[first] == PART_MATERIAL["skin"]
    if all(label in mesh.fp_labels for label in LIP_OUTLINE):
        outline = np.array([mesh.fp(label) for label in LIP_OUTLINE])
        lips[skin] = lip_weights(mesh.vertices[source[skin]], outline)
    detail = np.zeros((len(source), 2), np.float32)
    detail[skin] = brow_coordinates(mesh, mesh.vertices[source[skin]])
    nose = np.zeros((len(source), 2), np.float32)
    nose[skin] = nose_coordinates(mesh, mesh.vertices[source[skin]])
    for part in ("teeth_upper", "teeth_lower"):
        if part in mesh.part_ranges and len(mesh.triangles.get(part, ())):
            a, b = mesh.part_ranges[part]
            arch = tooth_coordinates(mesh.vertices[a:b], upper=part == "teeth_upper")
            mine = (source >= a) & (source < b)
            detail[mine] = arch[source[mine] - a]
    return SceneLayout(
        source=source,
        uv=corner_uv[first].astype(np.float32),
        material=corner_mat[first].astype(np.float32),
        lips=lips,
        cavity=cavity_weights(mesh)[source].astype(np.float32),
        detail=detail,
        nose=nose,
        indices=inverse.reshape(-1, 3).astype(np.uint32),
        triangles=tri,
        incidence=incidence_matrix(tri, mesh.n_vertices),
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
    return out
