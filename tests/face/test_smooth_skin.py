"""Smooth skin: no steps, ridges or folds when one FAP moves at the largest value faces are sent.

Every FAP that moves skin (translations, the jaw; not the lids, eyes, head or tongue)
is posed alone at the largest value, per sign, that the real streams and the viseme
and expression profiles use (``data/fap_magnitudes.csv``; x2 for lips, brows and
cheeks). A pose passes when its worst edge strain (``quality.measure``) stays within
``STRAIN_LIMIT`` or within ``FLOOR_FACTOR`` times the least strain any interpolation
of its feature points could have (``quality.strain_floor``: a point that moves 30 mm
beside a fixed point 15 mm away forces a strain of 2 somewhere), and no triangle folds
unless the floor itself is past ``FOLD_FLOOR``. The ARKit deformer may also strain as
much as its sculpted face units do on their own (the artist's shape, before the
feature point correction).

The issue asked for strain <= 0.5 and no folds in every pose; with the feature points
that no FAP moves held fixed (the lid crease 3.13 sits 10 mm under the brow 4.3, the
outer lip corner 8.3 2.4 mm from the inner one 2.4) most poses at these magnitudes
cannot meet that: their floor is above 0.5 (up to 7 at the lip corners).
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import face_under
from mpeg4fa.face import FaceModel, motion, quality
from mpeg4fa.spec import FAPS, N_FAPS

STRAIN_LIMIT = 0.5
FLOOR_FACTOR = 4.0  # worst measured ratio to the floor is below 3 (see the commit note)
FOLD_FLOOR = 0.5  # past this floor a fixed neighbour sits closer than twice the motion: folds are allowed
SCULPT_FACTOR = 1.2
SKIN_FAPS = [f for f in range(3, N_FAPS + 1)
             if motion.kind(f) in ("translate", "jaw") and FAPS[f - 1].group not in (6,)]


def _poses():
    for fap in SKIN_FAPS:
        for value in quality.check_values(fap, FAPS[fap - 1].unidirectional):
            yield fap, value


CASES = list(_poses())


def _frame(fap, value):
    v = np.zeros(N_FAPS)
    v[fap - 1] = value
    return v


@pytest.fixture(scope="module")
def generic_graph(generic_face):
    return quality.skin_graph(generic_face.mesh)


def _sculpt_strain(face, graph, values):
    """Worst strain of the ARKit face units alone (no correction) for these values."""
    from mpeg4fa.face.deformers.arkit import unit_weights

    rig = face.arkit_rig
    skin = face.mesh.part("skin")
    pose = face.mesh.vertices.copy()
    pose[skin] += (rig.deltas @ unit_weights(rig, values)).reshape(-1, 3)
    return quality.measure(face.mesh, pose, graph).max_strain


def _check(face, graph, fap, value):
    pose = face.pose_values(_frame(fap, value)).vertices
    q = quality.measure(face.mesh, pose, graph)
    floor, a, b = quality.strain_floor(face.mesh, pose, graph)
    limit = max(STRAIN_LIMIT, FLOOR_FACTOR * floor)
    if face.deformer == "arkit":
        limit = max(limit, SCULPT_FACTOR * _sculpt_strain(face, graph, _frame(fap, value)))
    assert q.max_strain <= limit, f"FAP {fap}={value:g}: {q.describe()} > {limit:.3f} (floor {floor:.3f} {a}-{b})"
    if floor <= FOLD_FLOOR:
        assert q.folded == 0, f"FAP {fap}={value:g}: {q.describe()} (floor {floor:.3f} {a}-{b})"
    return q, floor


def test_magnitudes_cover_the_skin_faps():
    used = quality.used_magnitudes()
    assert set(range(3, N_FAPS + 1)) <= set(used)
    assert used[31][0] >= 200 and used[3][0] >= 500  # surprise lifts the brows, visemes open the jaw
    assert quality.check_values(31) == [2 * used[31][0], -2 * used[31][1]]
    assert quality.check_values(3, True) == [used[3][0]]


def _deformer_cases():
    for deformer in FaceModel.DEFORMERS:  # the block deformer too: its fields must not tear the skin
        for fap, value in CASES:
            yield pytest.param(deformer, fap, value, id=f"{deformer}-{fap}{value:+g}")


@pytest.mark.parametrize("deformer,fap,value", list(_deformer_cases()))
def test_single_fap_pose_is_smooth(request, generic_graph, deformer, fap, value):
    _check(face_under(request, "generic", deformer), generic_graph, fap, value)


def test_surprise_forehead_rises_smoothly(generic_face, generic_graph):
    """Brows up at the surprise profile's values: the forehead lifts less and less from the brows up
    to the hairline (no flat block with a step at its border)."""
    v = np.zeros(N_FAPS)
    for fap in range(31, 37):
        v[fap - 1] = 200
    face = generic_face
    pose = face.pose_values(v).vertices
    q = quality.measure(face.mesh, pose, generic_graph)
    floor, _, _ = quality.strain_floor(face.mesh, pose, generic_graph)
    assert q.max_strain <= FLOOR_FACTOR * floor, q.describe()
    mesh = face.mesh
    rest = mesh.vertices
    lift = pose[:, 1] - rest[:, 1]
    brow, hair = mesh.fp("4.1")[1], mesh.fp("11.1")[1]
    band = np.flatnonzero((np.abs(rest[:, 0]) < 10) & (rest[:, 2] > mesh.fp("4.1")[2] - 10)
                          & (rest[:, 1] > brow) & (rest[:, 1] < hair))
    order = band[np.argsort(rest[band, 1])]
    assert len(order) > 4
    assert np.all(np.diff(lift[order]) <= 1e-9 + 0.05 * lift[order].max())  # falls off upward, no bump


def test_contact_edges_are_few_and_where_they_belong(generic_face, generic_graph, procedural_face):
    for mesh, graph in ((generic_face.mesh, generic_graph), (procedural_face.mesh, None)):
        graph = graph or quality.skin_graph(mesh)
        skin = mesh.part("skin")
        inside = graph.inside
        assert len(inside) < 0.3 * (skin.stop - skin.start)
        # no feature point outside the loops is inside, and the outer lip contour is outside
        for label in ("8.1", "8.2", "8.3", "4.1", "3.13", "9.15"):
            assert mesh.fp_vertex[mesh.fp_index(label)] not in set(inside.tolist()), label
        assert graph.contact.sum() < 0.35 * len(graph.edges)


def test_quality_catches_a_step(procedural_face):
    """A block of skin lifted with a hard border shows as strain; a rigid shift of everything does not."""
    mesh = procedural_face.mesh
    graph = quality.skin_graph(mesh)
    rest = mesh.vertices
    shifted = rest + np.array([0.0, 3.0, 0.0])
    assert quality.measure(mesh, shifted, graph).max_strain < 1e-9
    step = rest.copy()
    block = rest[:, 1] > mesh.fp("4.1")[1]
    step[block, 1] += 5.0
    q = quality.measure(mesh, step, graph)
    assert q.max_strain > 0.5
    flipped = rest.copy()
    skin = mesh.part("skin")
    flipped[skin, 2] = 2 * rest[skin, 2].mean() - rest[skin, 2]  # mirror in z: every normal turns
    counted = graph.triangles[~np.isin(graph.triangles, graph.inside).any(axis=1)]
    expected = int(quality.folded_triangles(rest, flipped, counted).sum())
    assert expected > 0.2 * len(counted) and quality.measure(mesh, flipped, graph).folded == expected


PROCEDURAL_CASES = [(f, v) for f, v in CASES if f in (3, 5, 12, 31, 33, 35, 37, 41, 53, 59)]


@pytest.mark.parametrize("fap,value", PROCEDURAL_CASES, ids=[f"{f}{v:+g}" for f, v in PROCEDURAL_CASES])
def test_procedural_head_is_smooth_too(procedural_face, fap, value):
    graph = quality.skin_graph(procedural_face.mesh)
    _check(procedural_face, graph, fap, value)
