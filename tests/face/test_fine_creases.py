"""The rest skin's fine creases, flattened on loading (:mod:`mpeg4fa.face.fine_creases`): few vertices,
less than half a millimetre, nothing a FAP names, the head still mirror symmetric; and why: without it
the brows raised twice their extreme leave a fold line at each outer eye corner."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.face import FaceModel, creases, quality
from mpeg4fa.face.asset import head_path
from mpeg4fa.face.fine_creases import CREASE_DEGREES, TINY_MM2, fine_crease_vertices, flatten_fine_creases
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.neck import smooth_rim
from mpeg4fa.face.regions import triangle_pairs, unit_normals


@pytest.fixture(scope="module")
def unflattened(generic_face):
    """The generic head as loaded before the flattening (the same file, the rim smoothed)."""
    return smooth_rim(HeadMesh.load(head_path()))


def _pair_angles(mesh: HeadMesh) -> np.ndarray:
    """Degrees between each pair of neighbouring skin triangles, and their larger area (mm^2)."""
    tris = np.asarray(mesh.triangles["skin"])
    a, b = triangle_pairs(tris)
    n = unit_normals(mesh.vertices, tris)
    p = mesh.vertices[tris]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", n[a], n[b]), -1, 1))), np.maximum(area[a], area[b])


def test_few_vertices_move_a_little_and_no_feature_point(generic_face, unflattened):
    rows = fine_crease_vertices(unflattened)
    moved = np.linalg.norm(generic_face.mesh.vertices - unflattened.vertices, axis=1)
    assert 0 < len(rows) <= 16 and set(np.flatnonzero(moved > 0)) <= set(rows)
    assert moved.max() < 0.5
    assert np.all(moved[generic_face.mesh.fp_vertex] == 0)
    v, m = generic_face.mesh.vertices, generic_face.mesh.mirror
    assert np.array_equal(v[:, 0], -v[m, 0]) and np.array_equal(v[:, 1:], v[m, 1:])


def test_the_creases_open(generic_face, unflattened):
    """The tiny pairs creased at rest whose vertices move open (49 to 11 degrees at the outer eye corners);
    the others (the lip corners', whose step would sharpen them) stay as they were."""
    before, area = _pair_angles(unflattened)
    after, _ = _pair_angles(generic_face.mesh)
    creased = (before > CREASE_DEGREES[0]) & (before < CREASE_DEGREES[1]) & (area <= TINY_MM2)
    tris = np.asarray(unflattened.triangles["skin"])
    a, b = triangle_pairs(tris)
    moved = np.isin(tris[a], fine_crease_vertices(unflattened)).all(axis=1)
    assert (creased & moved).sum() >= 2
    assert after[creased & moved].max() < 20 and np.all(after[creased & ~moved] <= before[creased & ~moved])


def test_a_mesh_without_fine_creases_is_left_alone(procedural_head):
    """The procedural head's skin is coarse and smooth: nothing to flatten, the same mesh back."""
    assert len(fine_crease_vertices(procedural_head)) == 0
    assert flatten_fine_creases(procedural_head) is procedural_head


def test_unflattened_the_cheek_lift_draws_more_fold_lines(generic_face, unflattened):
    """The measure sees fold lines the flattening removes (on the feature-point deformer): cheek l at 600, 17 fold
    lines unflattened, 14 flattened. (Brows raised x2 showed it first, a pair of fold lines at the outer eye corners;
    since a raise holds the upper lids' front edges, 2026-12-07, they fold there neither way.)"""
    values = creases.crease_poses(generic_face)["cheek l 600"]
    old = FaceModel(unflattened)
    before = creases.measure_pose(old, values, quality.skin_graph(unflattened)).flipped
    after = creases.measure_pose(generic_face, values, quality.skin_graph(generic_face.mesh)).flipped
    assert before > after, (before, after)
