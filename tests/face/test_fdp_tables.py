"""FDP case 4: a FaceDefTable moves its vertices by exactly its amount per FAP unit, on any head."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.face import FaceError, FaceModel
from mpeg4fa.face.deformers import names
from mpeg4fa.face.deformers.tables import unused_tables
from mpeg4fa.fdp.model import FaceDefMesh, FaceDefTable, FaceDefTransform

OPEN_JAW, RAISE_B_MIDLIP, HEAD_PITCH = 3, 5, 48


@pytest.fixture(scope="module")
def face(procedural_face) -> FaceModel:
    return procedural_face


def _skin_vertex(face: FaceModel, label: str = "8.1") -> int:
    return int(face.mesh.fp_vertex[face.mesh.fp_labels.index(label)])


def test_one_vertex_moves_exactly_by_the_table(face):
    v = _skin_vertex(face)
    per_unit = np.array([0.002, -0.01, 0.004])  # mm per FAP unit
    table = FaceDefTable(fap=RAISE_B_MIDLIP, meshes=(FaceDefMesh([v], [-1000, 1000], [[per_unit]]),))
    tabled = face.with_deformer("tables", tables=(table,))
    values = np.zeros(68)
    values[RAISE_B_MIDLIP - 1] = 300
    moved = tabled.pose_values(values).vertices
    neutral = tabled.neutral().vertices
    np.testing.assert_allclose(moved[v] - neutral[v], 300 * per_unit, atol=1e-12)
    # the FAP is the table's alone: every other vertex stays where it was
    others = np.delete(np.arange(len(moved)), v)
    np.testing.assert_array_equal(moved[others], neutral[others])
    # without the table the feature-point deformer moves many vertices for the same FAP
    plain = face.pose_values(values).vertices
    assert (np.linalg.norm(plain - face.neutral().vertices, axis=1) > 1e-6).sum() > 10


def test_piecewise_intervals_and_clamping(face):
    v = _skin_vertex(face, "2.1")
    slopes = [[[0, 0.02, 0], [0, -0.01, 0]]]  # up 0.02 mm/unit below 0, down 0.01 mm/unit above it
    table = FaceDefTable(fap=OPEN_JAW, meshes=(FaceDefMesh([v], [-200, 0, 500], slopes),))
    tabled = face.with_deformer("tables", tables=(table,))
    base = tabled.neutral().vertices[v]
    for value, dy in ((400, -4.0), (500, -5.0), (900, -5.0)):  # beyond the last border the motion stops
        values = np.zeros(68)
        values[OPEN_JAW - 1] = value
        assert tabled.pose_values(values).vertices[v, 1] - base[1] == pytest.approx(dy, abs=1e-12)


def test_faps_without_a_table_move_as_the_feature_point_deformer(face):
    v = _skin_vertex(face)
    table = FaceDefTable(fap=RAISE_B_MIDLIP, meshes=(FaceDefMesh([v], [0, 10], [[[0, 1.0, 0]]]),))
    tabled = face.with_deformer("tables", tables=(table,))
    values = np.zeros(68)
    values[OPEN_JAW - 1] = 400
    np.testing.assert_array_equal(tabled.pose_values(values).vertices, face.pose_values(values).vertices)


def test_transform_turns_the_whole_mesh(face):
    per_unit = 1e-5  # radians per unit, as the head rotation FAPs
    table = FaceDefTable(fap=HEAD_PITCH, transforms=(FaceDefTransform("rotation", rotation=[1, 0, 0, per_unit]),))
    tabled = face.with_deformer("tables", tables=(table,))
    values = np.zeros(68)
    values[HEAD_PITCH - 1] = 10000  # 0.1 rad about x, through the mesh's origin
    p = tabled.pose_values(values).vertices
    q = tabled.neutral().vertices
    c, s = np.cos(0.1), np.sin(0.1)
    expected = q @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]]).T
    np.testing.assert_allclose(p, expected, atol=1e-9)


def test_tables_are_kept_through_calibration_and_checked(face):
    v = _skin_vertex(face)
    table = FaceDefTable(fap=RAISE_B_MIDLIP, meshes=(FaceDefMesh([v], [0, 10], [[[0, 1.0, 0]]]),))
    tabled = face.with_deformer("tables", tables=(table,))
    assert tabled.calibrate(face.to_fdp()).deformer_options["tables"] == (table,)
    far = FaceDefTable(fap=RAISE_B_MIDLIP, meshes=(FaceDefMesh([face.mesh.n_vertices], [0, 10], [[[0, 1, 0]]]),))
    with pytest.raises(FaceError, match="moves vertex"):
        face.with_deformer("tables", tables=(far,)).neutral()
    with pytest.raises(FaceError, match="not a list of FaceDefTable"):
        face.with_deformer("tables", tables=[1, 2])


def test_high_level_tables_are_named_as_unused_and_the_deformer_is_not_a_user_choice():
    tables = (FaceDefTable(fap=1, high_level_select=3), FaceDefTable(fap=OPEN_JAW))
    assert unused_tables(tables) == [1]
    assert "tables" not in names()


# ---- FDP case 4: the sender's mesh, rigged, moved by its tables ---------------------------------


def _case4(face: FaceModel, units: float = 1.0):
    """The face's skin as a sender's FDP mesh (in ``units`` of a mm), one table moving 8.1's vertex."""
    from mpeg4fa.fdp import Fdp, FdpMesh

    sent = face.to_fdp(with_mesh=True)
    skin = face.mesh.part("skin")
    v = _skin_vertex(face) - skin.start
    mesh = FdpMesh(vertices=sent.mesh.vertices * units, triangles=sent.mesh.triangles, name="skin")
    per_unit = np.array([0.0, -0.01, 0.003])
    table = FaceDefTable(fap=RAISE_B_MIDLIP, meshes=(FaceDefMesh([v], [0, 1000], [[per_unit * units]]),))
    fdp = Fdp(labels=sent.labels, points=np.asarray(sent.points) * units, mesh=mesh, tables=(table,))
    return fdp, v, per_unit


@pytest.mark.parametrize("units", [1.0, 0.001])  # millimetres, and a sender working in metres
def test_case4_plays_the_senders_mesh_moved_by_its_table(face, units):
    from mpeg4fa.face.sent import played_face

    fdp, v, per_unit = _case4(face, units)
    played = played_face(fdp)
    skin = played.mesh.part("skin")
    assert played.deformer == "tables" and skin.stop - skin.start == len(fdp.mesh.vertices)
    here = int(played.mesh.info["head_vertex"][v])
    values = np.zeros(68)
    values[RAISE_B_MIDLIP - 1] = 250
    moved = played.pose_values(values).vertices - played.neutral().vertices
    np.testing.assert_allclose(moved[here], 250 * per_unit, atol=1e-9)  # the rig's frame is in mm
    assert np.count_nonzero(np.linalg.norm(moved, axis=1) > 1e-12) == 1
    values[:] = 0
    values[OPEN_JAW - 1] = 300  # no table: the rig opens the jaw
    assert np.linalg.norm(played.pose_values(values).vertices - played.neutral().vertices, axis=1).max() > 1.0


def test_case4_without_the_points_a_rig_needs_falls_back_to_the_generic_head(face, generic_head_installed):
    from mpeg4fa.face.sent import TablesWarning, played_face
    from mpeg4fa.fdp import Fdp

    fdp, _, _ = _case4(face)
    keep = [i for i, label in enumerate(fdp.labels) if label != "2.1"]
    partial = Fdp(labels=[fdp.labels[i] for i in keep], points=np.asarray(fdp.points)[keep], mesh=fdp.mesh,
                  tables=fdp.tables)
    with pytest.warns(TablesWarning, match="cannot be played.*2.1"):
        played = played_face(partial)
    assert played.deformer == "fap" and played.calibration is not None
