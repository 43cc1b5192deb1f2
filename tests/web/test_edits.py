"""The editor's pure operations on meshes the tests make (trimesh's icosphere) and on the heads."""
import numpy as np
import pytest
import trimesh

from mpeg4fa.face.fapu import measure_fapu
from mpeg4fa.spec import FEATURE_POINT_MIRROR
from mpeg4fa.web import edits
from mpeg4fa.web.session import Session


def sphere() -> edits.EditMesh:
    s = trimesh.creation.icosphere(subdivisions=2)
    return edits.make_mesh(s.vertices, s.faces)


def watertight(m: edits.EditMesh) -> bool:
    t = trimesh.Trimesh(m.vertices, m.triangles, process=False)
    return t.is_watertight and t.is_winding_consistent and t.volume > 0


def test_fill_hole_closes_a_deleted_fan():
    m = sphere()
    fan = np.flatnonzero((m.triangles == 0).any(axis=1))
    ring = sorted(set(m.triangles[fan].ravel()) - {0})
    holed = edits.delete_faces(m, fan)  # vertex 0 only served the fan: it goes, the ring shifts by one
    assert len(holed.vertices) == len(m.vertices) - 1 and not watertight(holed)
    closed = edits.fill_hole(holed, [v - 1 for v in ring])
    assert watertight(closed)
    assert len(closed.triangles) == len(m.triangles) - 2


def test_delete_vertices_then_fill_any_order():
    m = edits.delete_vertices(sphere(), [5])
    t = trimesh.Trimesh(m.vertices, m.triangles, process=False)
    loop = np.unique(t.edges[trimesh.grouping.group_rows(t.edges_sorted, require_count=1)])
    assert watertight(edits.fill_hole(m, loop[::-1].tolist()))


def test_fill_hole_refuses_what_is_not_one_loop():
    with pytest.raises(edits.EditError, match="boundary loop"):
        edits.fill_hole(sphere(), [0, 1, 2])


def test_connected_region_and_split_part():
    a, b = trimesh.creation.icosphere(1), trimesh.creation.box()
    both = edits.make_mesh(np.vstack([a.vertices, b.vertices + 5]),
                           np.vstack([a.faces, b.faces + len(a.vertices)]))
    region = edits.connected_region(both, len(a.faces))
    assert region.tolist() == list(range(len(a.faces), len(a.faces) + len(b.faces)))
    split = edits.split_part(both, region, "teeth_upper")
    assert split.part_names == ("skin", "teeth_upper")
    assert split.parts.count("teeth_upper") == len(b.faces)
    assert edits.connected_region(split, 0, same_part=True).tolist() == list(range(len(a.faces)))
    gone = edits.delete_part(split, "teeth_upper")
    assert gone.part_names == ("skin",) and len(gone.vertices) == len(a.vertices)
    with pytest.raises(edits.EditError, match="bad part name"):
        edits.split_part(both, [0], "../x")


def test_move_vertices():
    m = sphere()
    moved = edits.move_vertices(m, [1, 2], delta=[1, 0, 0])
    assert np.allclose(moved.vertices[[1, 2]] - m.vertices[[1, 2]], [1, 0, 0])
    placed = edits.move_vertices(m, [3], positions=[[9, 9, 9]])
    assert placed.vertices[3].tolist() == [9, 9, 9] and np.array_equal(m.vertices, sphere().vertices)


def test_undo_redo_restore_arrays_exactly():
    s = Session(sphere())
    first = s.mesh
    s.apply(lambda m: edits.delete_faces(m, [0, 1, 2]))
    s.apply(lambda m: edits.assign_point(m, "2.1", 4))
    after = s.mesh
    assert s.undo().same(edits.delete_faces(first, [0, 1, 2]))
    assert s.undo() is first and first.same(sphere())
    s.redo()
    assert s.redo().same(after)
    with pytest.raises(edits.EditError, match="nothing to redo"):
        s.redo()


def test_points_follow_deletions():
    m = edits.assign_point(sphere(), "2.1", 10)
    m = edits.delete_vertices(m, [3])
    assert m.points == {"2.1": 9}
    assert edits.delete_vertices(m, [9]).points == {}


def test_mirror_points_puts_twins_at_the_mirror_vertex():
    m = sphere()
    left = int(np.argmax(m.vertices[:, 0] - 0.1 * m.vertices[:, 1]))
    m = edits.assign_point(m, "3.5", left)
    mirrored = edits.mirror_points(m)
    twin = mirrored.points[FEATURE_POINT_MIRROR["3.5"]]
    assert FEATURE_POINT_MIRROR["3.5"] == "3.6"
    assert np.allclose(m.vertices[twin], m.vertices[left] * [-1, 1, 1])


def test_head_points_give_the_engines_fapu_and_pass_validation(procedural_face):
    m = edits.from_head(procedural_face.mesh)
    assert edits.fapu(m) == procedural_face.fapu
    assert edits.validate(m) == []
    assert "feature points not placed" in edits.validate(edits.clear_point(m, "2.1"))[0]
    assert edits.validate(edits.clear_point(m, "2.1"), ["3.5"]) == []


@pytest.mark.usefixtures("generic_head_installed")
def test_fapu_matches_the_generic_head(generic_face):
    m = edits.from_head(generic_face.mesh)
    assert edits.fapu(m).as_dict() == measure_fapu(generic_face.feature_points()).as_dict()
    assert edits.validate(m) == []


def test_validation_finds_degenerate_faces_and_open_eyes():
    m = sphere()
    flat = edits.make_mesh(np.vstack([m.vertices, [[0, 0, 0]] * 3]),
                           np.vstack([m.triangles, [[len(m.vertices)] * 2 + [len(m.vertices) + 1]]]))
    assert any("degenerate" in p for p in edits.validate(flat, []))
    eye = edits.split_part(edits.delete_faces(m, [0]), range(len(m.triangles) - 1), "eye_l")
    assert any("eye_l must be closed" in p for p in edits.validate(eye, []))
    assert edits.validate(m, []) == []


def test_a_foreign_mesh_poses_through_the_calibrated_head(procedural_face):
    """With no link to the head's vertices, a mesh is posed through the head calibrated to its points:
    the head itself, so read as foreign, poses as the engine poses it."""
    from dataclasses import replace

    from mpeg4fa.web.posing import pose_values, posed_vertices

    head = edits.from_head(procedural_face.mesh)
    foreign = replace(head, origin=np.full(len(head.vertices), -1))
    values = pose_values({3: 400, 51: -100})
    expected = procedural_face.deform(values).vertices
    assert np.abs(posed_vertices(foreign, procedural_face, values) - expected).max() < 1e-6
    assert np.abs(posed_vertices(head, procedural_face, values) - expected).max() < 1e-9
    with pytest.raises(edits.EditError, match="place feature points"):
        posed_vertices(replace(foreign, points={}), procedural_face, values)
