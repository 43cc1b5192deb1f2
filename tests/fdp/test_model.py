"""The FDP data model: construction, checks, conveniences, and the FaceDefMesh/Transform semantics."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

from mpeg4fa import spec
from mpeg4fa.fdp import (FaceDefMesh, FaceDefTable, FaceDefTransform, Fdp, FdpError, FdpMesh, FdpValueError,
                         TextureImage)
from mpeg4fa.fdp.model import FAPU_KEYS, LABELS
from mpeg4fa.formats import FormatError


def small_mesh() -> FdpMesh:
    return FdpMesh(np.arange(15.0).reshape(5, 3), [[0, 1, 2], [2, 3, 4]], name="skin")


# ---- Fdp construction --------------------------------------------------------------------------


def test_labels_are_the_84_standard_labels_in_order():
    assert len(LABELS) == 84
    assert LABELS == tuple(fp.label for fp in spec.FEATURE_POINTS)
    assert LABELS.index("3.14") < LABELS.index("4.1")
    assert LABELS.index("2.2") < LABELS.index("2.10")


def test_from_points_keeps_standard_order_with_rows():
    fdp = Fdp.from_points({"11.6": [1, 2, 3], "2.10": [4, 5, 6], "2.2": [7, 8, 9]},
                          texture_coords={"11.6": [0.1, 0.2], "2.10": [0.3, 0.4], "2.2": [0.5, 0.6]})
    assert fdp.labels == ("2.2", "2.10", "11.6")
    assert fdp.points.tolist() == [[7, 8, 9], [4, 5, 6], [1, 2, 3]]
    assert fdp.texture_coords.tolist() == [[0.5, 0.6], [0.3, 0.4], [0.1, 0.2]]
    assert fdp.points.dtype == np.float64
    np.testing.assert_array_equal(fdp.point("2.10"), [4, 5, 6])
    assert list(fdp.as_dict()) == ["2.2", "2.10", "11.6"]


def test_arrays_are_copied_and_read_only():
    source = np.array([[1.0, 2.0, 3.0]])
    fdp = Fdp(("2.1",), source)
    source[0, 0] = 99
    assert fdp.points[0, 0] == 1.0
    with pytest.raises(ValueError):
        fdp.points[0, 0] = 5
    with pytest.raises(AttributeError):
        fdp.name = "other"  # type: ignore[misc]


def test_equality_compares_arrays_by_value_and_objects_are_unhashable():
    a = Fdp.from_points({"2.1": [0, 1, 2]}, mesh=small_mesh(), name="x")
    b = Fdp.from_points({"2.1": [0.0, 1.0, 2.0]}, mesh=small_mesh(), name="x")
    assert a == b
    assert a != Fdp.from_points({"2.1": [0, 1, 2.5]}, mesh=small_mesh(), name="x")
    assert a != Fdp.from_points({"2.1": [0, 1, 2]}, name="x")
    with pytest.raises(TypeError):
        hash(a)


def test_subset_and_head_height():
    fdp = Fdp.from_points({"2.1": [0, -5, 0], "11.4": [0, 7, 0], "9.3": [0, 0, 2]},
                          texture_coords={"2.1": [0, 0], "11.4": [1, 1], "9.3": [0.5, 0.5]})
    sub = fdp.subset(["9.3", "2.1"])
    assert sub.labels == ("2.1", "9.3")
    assert sub.texture_coords.tolist() == [[0, 0], [0.5, 0.5]]
    assert fdp.head_height() == 12.0
    with pytest.raises(KeyError, match="4.1"):
        fdp.subset(["4.1"])
    with pytest.raises(KeyError, match="not a feature point label"):
        fdp.point("99.9")
    with pytest.raises(ValueError):
        Fdp((), np.zeros((0, 3))).head_height()


def test_empty_fdp_is_valid():
    fdp = Fdp((), [])
    assert fdp.points.shape == (0, 3) and fdp.labels == ()


@pytest.mark.parametrize("labels, points, message, where", [
    (("2.1", "12.1"), [[0, 0, 0], [1, 1, 1]], "unknown feature point label '12.1'", ("feature_points", "12.1")),
    (("2.1", "2.1"), [[0, 0, 0], [1, 1, 1]], "2.1 given twice", ("feature_points", "2.1")),
    (("2.1",), [[0, 0]], r"shape \(n, 3\)", ("feature_points",)),
    (("2.1", "2.2"), [[0, 0, 0]], "2 labels but 1 points", ("feature_points",)),
    (("2.1", "2.2"), [[0, 0, 0], [0, np.inf, 0]], "finite", ("feature_points", "2.2")),
    (("2.1",), [["a", 0, 0]], "array of numbers", ("feature_points",)),
])
def test_bad_points_raise_value_error_with_path(labels, points, message, where):
    with pytest.raises(FdpValueError, match=message) as info:
        Fdp(labels, points)
    assert isinstance(info.value, ValueError)
    assert info.value.field == where


def test_a_single_string_is_not_a_label_sequence():
    with pytest.raises(FdpValueError, match="not one string"):
        Fdp("2.1", [[0, 0, 0]])


def test_texture_coords_checks():
    with pytest.raises(FdpValueError, match=r"2.2 must lie in \[0, 1\]") as info:
        Fdp(("2.1", "2.2"), np.zeros((2, 3)), texture_coords=[[0, 0], [1.5, 0]])
    assert info.value.field == ("texture_coords", "2.2")
    with pytest.raises(FdpValueError, match="2 feature points but 1 texture"):
        Fdp(("2.1", "2.2"), np.zeros((2, 3)), texture_coords=[[0, 0]])
    with pytest.raises(FdpValueError, match="same labels"):
        Fdp.from_points({"2.1": [0, 0, 0]}, texture_coords={"2.2": [0, 0]})


def test_fapu_checks_and_canonical_order():
    fdp = Fdp((), [], fapu={"MW0": 3, "IRISD0": 1.5})
    assert list(fdp.fapu) == ["IRISD0", "MW0"] and fdp.fapu["MW0"] == 3.0
    assert FAPU_KEYS == ("IRISD0", "ES0", "ENS0", "MNS0", "MW0")
    with pytest.raises(FdpValueError, match="unknown FAPU distance 'AU'"):
        Fdp((), [], fapu={"AU": 1})
    with pytest.raises(FdpValueError, match="positive") as info:
        Fdp((), [], fapu={"ES0": 0})
    assert info.value.field == ("fapu", "ES0")
    with pytest.raises(FdpValueError, match="must be a number"):
        Fdp((), [], fapu={"ES0": "1"})


def test_texture_image_checks():
    tex = TextureImage("skin", "image/png", bytearray(b"\x89PNG"))
    assert tex.data == b"\x89PNG" and isinstance(tex.data, bytes)
    assert "4 bytes" in repr(tex)
    with pytest.raises(FdpValueError, match="type/subtype"):
        TextureImage("skin", "png", b"")
    with pytest.raises(FdpValueError, match="must be bytes"):
        TextureImage("skin", "image/png", "text")  # type: ignore[arg-type]
    with pytest.raises(FdpValueError, match="65535"):
        TextureImage("x" * 70000, "image/png", b"")
    with pytest.raises(FdpValueError, match="surrogate"):
        TextureImage("\ud800", "image/png", b"")


def test_mesh_checks():
    mesh = small_mesh()
    assert mesh.triangles.dtype == np.int64 and mesh.uvs is None
    with pytest.raises(FdpValueError, match=r"\[0, 4\], got 5") as info:
        FdpMesh(np.zeros((5, 3)), [[0, 1, 2], [2, 3, 5]])
    assert info.value.field == ("triangles", 1)
    with pytest.raises(FdpValueError, match="hold integers"):
        FdpMesh(np.zeros((3, 3)), [[0.0, 1.0, 2.0]])
    with pytest.raises(FdpValueError, match="3 vertices but 2 uvs"):
        FdpMesh(np.zeros((3, 3)), [[0, 1, 2]], uvs=np.zeros((2, 2)))
    with pytest.raises(FdpValueError, match="has none"):
        FdpMesh(np.zeros((0, 3)), [[0, 0, 0]])
    assert FdpMesh([], []).vertices.shape == (0, 3)


# ---- FaceDefMesh: piecewise-linear displacement, hand-computed --------------------------------


def two_interval_mesh() -> FaceDefMesh:
    # borders -10 | 0 | 20; vertex 0 moves (1,0,0) per unit below 0 and (0,2,0) per unit above;
    # vertex 1 moves (0,0,1) per unit below 0 and (1,1,1) per unit above.
    disp = np.array([[[1, 0, 0], [0, 2, 0]],
                     [[0, 0, 1], [1, 1, 1]]], dtype=float)
    return FaceDefMesh([3, 7], [-10, 0, 20], disp)


@pytest.mark.parametrize("value, expected", [
    (0, [[0, 0, 0], [0, 0, 0]]),
    (5, [[0, 10, 0], [5, 5, 5]]),          # 5 units inside interval [0, 20]
    (20, [[0, 40, 0], [20, 20, 20]]),
    (35, [[0, 40, 0], [20, 20, 20]]),      # clamped at the top border
    (-4, [[-4, 0, 0], [0, 0, -4]]),        # 4 units inside [-10, 0], negative direction
    (-10, [[-10, 0, 0], [0, 0, -10]]),
    (-1e9, [[-10, 0, 0], [0, 0, -10]]),    # clamped at the bottom border
    (2.5, [[0, 5, 0], [2.5, 2.5, 2.5]]),   # non-integer values are fine
])
def test_face_def_mesh_displace(value, expected):
    np.testing.assert_allclose(two_interval_mesh().displace(value), expected)


def test_face_def_mesh_three_intervals_sums_the_parts_crossed():
    # borders 0 | 10 | 20 | 40, one vertex, slopes 1, 3, 5 along x
    fdm = FaceDefMesh([0], [0, 10, 20, 40], [[[1, 0, 0], [3, 0, 0], [5, 0, 0]]])
    assert fdm.displace(25)[0, 0] == 10 * 1 + 10 * 3 + 5 * 5
    assert fdm.displace(-3)[0, 0] == 0  # below b0 = 0: clamped to 0, no motion
    np.testing.assert_array_equal(fdm.weights(15), [10, 5, 0])


def test_face_def_mesh_borders_not_around_zero_measure_from_the_nearest_border():
    fdm = FaceDefMesh([0], [10, 20], [[[1, 0, 0]]])
    assert fdm.displace(0)[0, 0] == 0
    assert fdm.displace(15)[0, 0] == 5
    assert fdm.displace(100)[0, 0] == 10


def test_face_def_mesh_checks():
    with pytest.raises(FdpValueError, match="strictly increasing") as info:
        FaceDefMesh([0], [0, 5, 5], np.zeros((1, 2, 3)))
    assert info.value.field == ("interval_borders", 2)
    with pytest.raises(FdpValueError, match="at least 2"):
        FaceDefMesh([0], [0], np.zeros((1, 0, 3)))
    with pytest.raises(FdpValueError, match=r"\(1, 2, 3\)"):
        FaceDefMesh([0], [0, 1, 2], np.zeros((1, 1, 3)))
    with pytest.raises(FdpValueError, match="int32|2147483647"):
        FaceDefMesh([0], [0, 2**31], np.zeros((1, 1, 3)))
    with pytest.raises(FdpValueError, match="finite") as info:
        FaceDefMesh([0, 1], [0, 1], [[[0, 0, 0]], [[0, np.nan, 0]]])
    assert info.value.field == ("displacements", 1)
    with pytest.raises(ValueError, match="finite"):
        two_interval_mesh().displace(float("nan"))
    empty = FaceDefMesh([], [0, 1], [])
    assert empty.displace(1).shape == (0, 3)


# ---- FaceDefTransform ------------------------------------------------------------------------------


def test_face_def_transform_at_scales_only_the_driven_field():
    rot = FaceDefTransform("rotation", rotation=[0, 1, 0, 0.01], translation=[5, 5, 5])
    at = rot.at(30)
    np.testing.assert_allclose(at.rotation, [0, 1, 0, 0.3])
    np.testing.assert_array_equal(at.translation, [0, 0, 0])  # not driven: identity
    scale = FaceDefTransform("scale", scale=[2, 1, 0.5]).at(0.5)
    np.testing.assert_allclose(scale.scale, [1.5, 1, 0.75])
    move = FaceDefTransform("translation", translation=[0, 0.1, 0]).at(-20)
    np.testing.assert_allclose(move.translation, [0, -2, 0])
    for field in ("scale", "translation"):
        assert FaceDefTransform(field, rotation=[1, 0, 0, 2], scale=[3, 3, 3], translation=[1, 2, 3]).at(0) \
            == FaceDefTransform(field)
    assert rot.at(0).rotation[3] == 0  # zero angle about the same axis


def test_face_def_transform_checks():
    with pytest.raises(FdpValueError, match="one of rotation, scale, translation"):
        FaceDefTransform("shear")
    with pytest.raises(FdpValueError, match="4 numbers"):
        FaceDefTransform("rotation", rotation=[0, 0, 1])
    with pytest.raises(FdpValueError, match="zero vector"):
        FaceDefTransform("rotation", rotation=[0, 0, 0, 1])
    with pytest.raises(FdpValueError, match="finite"):
        FaceDefTransform("scale", scale=[1, np.inf, 1])


# ---- FaceDefTable and cross-checks -------------------------------------------------------------------


def test_face_def_table_ranges():
    assert FaceDefTable(68).high_level_select == 1
    for bad in (0, 69, True, 3.0):
        with pytest.raises(FdpValueError, match="fap"):
            FaceDefTable(bad)  # type: ignore[arg-type]
    with pytest.raises(FdpValueError, match="high_level_select"):
        FaceDefTable(1, 65)
    with pytest.raises(FdpValueError, match="FaceDefMesh objects") as info:
        FaceDefTable(3, 1, meshes=("nope",))  # type: ignore[arg-type]
    assert info.value.field == ("meshes", 0)


def test_tables_need_the_mesh_they_index():
    table = FaceDefTable(3, 1, (FaceDefMesh([0, 9], [0, 1], np.zeros((2, 1, 3))),))
    with pytest.raises(FdpValueError, match="needs the FDP's mesh") as info:
        Fdp((), [], tables=(table,))
    assert info.value.field == ("face_def_tables", 0, "meshes", 0)
    with pytest.raises(FdpValueError, match="coord_index 9 is beyond the mesh's 5 vertices") as info:
        Fdp((), [], mesh=small_mesh(), tables=[table])
    assert info.value.field == ("face_def_tables", 0, "meshes", 0, "coord_index", 1)


def test_duplicate_tables_are_rejected_but_high_level_selects_differ():
    Fdp((), [], tables=(FaceDefTable(1, 1), FaceDefTable(1, 2)))
    with pytest.raises(FdpValueError, match="already has a table") as info:
        Fdp((), [], tables=(FaceDefTable(5), FaceDefTable(5)))
    assert info.value.field == ("face_def_tables", 1, "fap")


def test_repr_is_short():
    fdp = Fdp.from_points({"2.1": [0, 0, 0]}, mesh=small_mesh(), fapu={"MW0": 1}, name="n")
    text = repr(fdp)
    assert "1 points" in text and "5 vertices" in text and "MW0" in text and len(text) < 200


# ---- FdpError ------------------------------------------------------------------------------------------


def test_fdp_error_renders_each_kind_of_place():
    text = FdpError("face.json", 3, 7, "bad value", "fix it")
    assert str(text) == "face.json:3:7: bad value (fix it)"
    binary = FdpError.at_byte("face.fdp", 123, "problem", "hint")
    assert str(binary) == "face.fdp: byte 123: problem (hint)"
    assert binary.line is None and binary.column is None and binary.offset == 123
    whole = FdpError.no_place("gone.fdp", "no such file")
    assert str(whole) == "gone.fdp: no such file"
    assert str(FdpError("f.xml", 4, None, "p")) == "f.xml:4: p"
    assert isinstance(binary, FormatError) and isinstance(binary, ValueError)


def test_fdp_error_pickles_with_every_attribute():
    for err in (FdpError("a", 1, 2, "p", "h"), FdpError.at_byte("b", 9, "p"), FdpError.no_place("c", "p", "h")):
        back = pickle.loads(pickle.dumps(err))
        assert type(back) is FdpError and str(back) == str(err)
        assert (back.path, back.line, back.column, back.offset, back.problem, back.hint) == \
            (err.path, err.line, err.column, err.offset, err.problem, err.hint)
    value_error = pickle.loads(pickle.dumps(FdpValueError("m", ("a", 1))))
    assert value_error.field == ("a", 1) and value_error.where == "a/1" and str(value_error) == "a/1: m"
