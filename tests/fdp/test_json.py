"""The JSON form: exact round trips, readable output, and every fault at the right line:column."""
from __future__ import annotations

import json

import numpy as np
import pytest

from mpeg4fa.fdp import (FaceDefMesh, FaceDefTable, FaceDefTransform, Fdp, FdpError, FdpMesh, TextureImage,
                         fdp_from_json, fdp_to_json)

from .textpos import place

AWKWARD = [0.1, 1 / 3, -0.0, 5e-324, 1.7976931348623157e308, -1e-300, 123456789.123456789, 2.0**-1074 * 3]


def full_fdp() -> Fdp:
    rng = np.random.default_rng(7)
    mesh = FdpMesh(rng.normal(size=(6, 3)), [[0, 1, 2], [2, 3, 4], [4, 5, 0]], uvs=rng.random((6, 2)), name="skin")
    tables = (
        FaceDefTable(3, 1, (FaceDefMesh([0, 5], [-200, 0, 300], rng.normal(size=(2, 2, 3))),),
                     (FaceDefTransform("rotation", rotation=[1, 0, 0, 1e-5]),)),
        FaceDefTable(1, 4, (), (FaceDefTransform("scale", scale=[1.1, 1, 1]),)),
        FaceDefTable(48),
    )
    points = {label: rng.normal(size=3) for label in ("2.1", "2.10", "3.5", "3.6", "9.15", "11.6")}
    uv = {label: rng.random(2) for label in points}
    return Fdp.from_points(points, texture_coords=uv, textures=(TextureImage("skin", "image/png", bytes(range(256))),
                                                                 TextureImage("eyes", "image/jpeg", b"")),
                           mesh=mesh, tables=tables, fapu={"IRISD0": 16, "ES0": 69.5, "ENS0": 51, "MNS0": 30,
                                                           "MW0": 50}, name="Zoë")


def read(text: str) -> Fdp:
    return fdp_from_json(text, "face.json")


def error(text: str | bytes) -> FdpError:
    with pytest.raises(FdpError) as info:
        fdp_from_json(text, "face.json")
    return info.value


def assert_at(err: FdpError, text: str, needle: str, nth: int = 0, shift: int = 0) -> None:
    """The error is at ``needle`` (its ``nth`` occurrence), ``shift`` characters on."""
    line, column = place(text, needle, nth)
    assert (err.line, err.column) == (line, column + shift), str(err)
    assert str(err).startswith(f"face.json:{err.line}:{err.column}: ")


def doc(**parts) -> str:
    base = {"format": "mpeg4fa-fdp", "version": 1}
    base.update(parts)
    return json.dumps(base, indent=1)


# ---- round trips ------------------------------------------------------------------------------------


def test_full_round_trip_is_exact():
    fdp = full_fdp()
    assert read(fdp_to_json(fdp)) == fdp


@pytest.mark.parametrize("fdp", [
    Fdp((), []),
    Fdp.from_points({"2.1": [1, 2, 3]}),
    Fdp.from_points({"7.1": [0, 0, 0]}, fapu={}),
    Fdp.from_points({"2.1": [0, 0, 0], "4.6": [1, 1, 1]}, texture_coords={"2.1": [0, 1], "4.6": [1, 0]}),
    Fdp((), [], mesh=FdpMesh(np.zeros((0, 3)), np.zeros((0, 3), int))),
    Fdp((), [], tables=(FaceDefTable(2, 64),)),
    Fdp((), [], texture_coords=np.zeros((0, 2))),
])
def test_round_trip_of_optional_parts(fdp):
    assert read(fdp_to_json(fdp)) == fdp


def test_subsets_round_trip():
    fdp = full_fdp()
    for labels in (["2.1"], ["3.6", "11.6"], []):
        sub = fdp.subset(labels)
        assert read(fdp_to_json(sub)) == sub


def test_awkward_floats_round_trip_bit_for_bit():
    points = {label: [value, -value, value * 0.5] for label, value in zip(["2.1", "2.2", "2.3", "2.4", "2.5", "2.6",
                                                                            "2.7", "2.8"], AWKWARD)}
    fdp = Fdp.from_points(points)
    back = read(fdp_to_json(fdp))
    assert back.points.tobytes() == fdp.points.tobytes()  # -0.0 and subnormals included


def test_output_is_readable():
    text = fdp_to_json(full_fdp())
    lines = text.splitlines()
    assert lines[0] == "{" and lines[1] == ' "format": "mpeg4fa-fdp",' and lines[2] == ' "version": 1,'
    assert '"name": "Zoë"' in text  # UTF-8, not \\u escapes
    point_lines = [line for line in lines if line.strip().startswith('"2.10": [')]
    assert len(point_lines) == 2  # one point per line, in feature_points and in texture_coords
    assert text.endswith("}\n")
    assert text.index('"2.10"') < text.index('"3.5"') < text.index('"11.6"')


def test_bytes_and_bom_are_accepted():
    text = fdp_to_json(full_fdp())
    assert fdp_from_json(text.encode("utf-8")) == full_fdp()
    assert fdp_from_json("\ufeff" + text) == full_fdp()
    assert fdp_from_json(b"\xef\xbb\xbf" + text.encode()) == full_fdp()


def test_defaults_for_absent_optional_keys():
    fdp = read('{"format": "mpeg4fa-fdp", "version": 1}')
    assert fdp == Fdp((), [])
    fdp = read(doc(face_def_tables=[{"fap": 4}], feature_points={"2.1": [1, 2, 3]}))
    assert fdp.tables == (FaceDefTable(4, 1),)


# ---- syntax errors ------------------------------------------------------------------------------------


def test_json_syntax_error_has_its_line_and_column():
    text = '{\n "format": "mpeg4fa-fdp",\n "version": 1,\n "name": "x",,\n}'
    err = error(text)
    assert (err.line, err.column) == (4, 14)  # the second comma
    assert "invalid JSON" in err.problem


def test_non_utf8_bytes():
    err = error(b'{"format": "mpeg4fa-fdp",\n "name": "caf\xe9"}')
    assert (err.line, err.column) == (2, 14)
    assert "UTF-8" in err.problem


def test_nan_and_infinity_literals_are_refused_where_they_are():
    text = doc(feature_points={"2.1": [0, 1, 2]}).replace("2\n", "NaN\n")
    assert_at(error(text), text, "NaN")
    text = doc(feature_points={"2.1": [0, 1e308, 2]}).replace("1e+308", "1e999")
    err = error(text)
    assert_at(err, text, "1e999")
    assert "finite" in err.problem


def test_too_deep_nesting_is_an_fdp_error():
    text = '{"format": "mpeg4fa-fdp", "x": ' + "[" * 200000 + "]" * 200000 + "}"
    err = error(text)
    assert err.line == 1 and "deep" in err.problem


def test_too_long_integer_literal():
    text = '{"format": "mpeg4fa-fdp",\n "version": ' + "9" * 5000 + "}"
    err = error(text)
    assert (err.line, err.column) == (2, 13)


# ---- schema errors at the right place --------------------------------------------------------------


def test_unknown_label_points_at_its_key():
    text = doc(feature_points={"2.1": [0, 0, 0], "12.3": [1, 1, 1]})
    err = error(text)
    assert "unknown feature point label '12.3'" in err.problem
    assert_at(err, text, '"12.3"')


def test_wrong_length_coordinate_points_at_the_array():
    text = doc(feature_points={"2.1": [0, 0, 0], "2.2": [1, 1]})
    err = error(text)
    assert "must have 3 numbers, got 2" in err.problem
    assert_at(err, text, '"2.2"', shift=len('"2.2": '))


def test_non_number_points_at_the_element():
    text = '{"format": "mpeg4fa-fdp", "version": 1,\n "feature_points": {"2.1": [0, "one", 2]}}'
    err = error(text)
    assert_at(err, text, '"one"')
    assert "must be a number" in err.problem and "'one'" in err.problem


def test_booleans_are_not_numbers():
    text = '{"format": "mpeg4fa-fdp", "version": 1, "feature_points": {"2.1": [0, true, 2]}}'
    assert_at(error(text), text, "true")


def test_duplicate_key_points_at_the_second():
    text = '{"format": "mpeg4fa-fdp", "version": 1,\n "feature_points": {"2.1": [0, 0, 0],\n  "2.1": [1, 1, 1]}}'
    err = error(text)
    assert "given twice" in err.problem
    assert_at(err, text, '"2.1"', nth=1)


def test_unknown_key_is_named_with_the_known_ones():
    text = doc(feature_point={})
    err = error(text)
    assert_at(err, text, '"feature_point"')
    assert "feature_points" in err.hint


@pytest.mark.parametrize("text, needle, message", [
    ('[1, 2]', "[", "must be a JSON object"),
    ('{"version": 1}', "{", "lacks the required key 'format'"),
    ('{"format": "something", "version": 1}', '"something"', "format must be 'mpeg4fa-fdp'"),
    ('{"format": "mpeg4fa-fdp", "version": 2}', '2}', "version 2 is a newer version; this reader knows version 1"),
    ('{"format": "mpeg4fa-fdp", "version": "1"}', '"1"', "version must be an integer"),
    ('{"format": "mpeg4fa-fdp", "version": 1, "name": 5}', "5", "name must be a string"),
    ('{"format": "mpeg4fa-fdp", "version": 1, "feature_points": []}', "[]", "must be a JSON object"),
])
def test_top_level_errors(text, needle, message):
    err = error(text)
    assert message in err.problem
    assert_at(err, text, needle)


def test_texture_coords_must_match_feature_points():
    text = doc(feature_points={"2.1": [0, 0, 0]}, texture_coords={"2.1": [0, 0], "2.2": [1, 1]})
    err = error(text)
    assert "'2.2', which has no feature point" in err.problem
    assert_at(err, text, '"2.2"')
    text = doc(feature_points={"2.1": [0, 0, 0], "2.2": [1, 1, 1]}, texture_coords={"2.1": [0, 0]})
    err = error(text)
    assert "lacks point 2.2" in err.problem
    assert_at(err, text, '"texture_coords"', shift=len('"texture_coords": '))
    text = doc(feature_points={"2.1": [0, 0, 0]}, texture_coords={"2.1": [0, 2]})
    err = error(text)
    assert "[0, 1]" in err.problem
    assert_at(err, text, '"2.1"', nth=1, shift=len('"2.1": '))


def test_fapu_errors():
    text = doc(fapu={"ES0": 1, "AU": 2})
    assert_at(error(text), text, '"AU"')
    text = doc(fapu={"ES0": -1})
    err = error(text)
    assert "positive" in err.problem
    assert_at(err, text, '-1')


def test_texture_errors():
    text = doc(textures=[{"name": "a", "media_type": "image/png", "data_base64": "AAA*"}])
    err = error(text)
    assert "base64" in err.problem
    assert_at(err, text, '"AAA*"')
    text = doc(textures=[{"name": "a", "media_type": "png", "data_base64": ""}])
    err = error(text)
    assert "type/subtype" in err.problem
    assert_at(err, text, '"png"')
    text = doc(textures=[{"name": "a", "data_base64": ""}])
    assert "lacks the required key 'media_type'" in error(text).problem


def test_mesh_errors_point_at_the_triangle():
    text = ('{"format": "mpeg4fa-fdp", "version": 1, "mesh": {\n "vertices": [[0,0,0], [1,0,0], [0,1,0]],\n'
            ' "triangles": [[0, 1, 2],\n   [2, 1, 3]]}}')
    err = error(text)
    assert "must lie in [0, 2], got 3" in err.problem
    assert_at(err, text, "[2, 1, 3]")
    text = text.replace("[2, 1, 3]", "[2, 1, -1]")
    err = error(text)
    assert_at(err, text, "-1")
    text = text.replace("[2, 1, -1]", "[2, 1]")
    assert_at(error(text), text, "[2, 1]")
    text = '{"format": "mpeg4fa-fdp", "version": 1, "mesh": {"vertices": [[0,0,0]], "triangles": [], "uvs": [[0]]}}'
    assert_at(error(text), text, "[0]]")


def test_table_errors():
    mesh = {"vertices": [[0, 0, 0]] * 4, "triangles": [[0, 1, 2]]}
    good = {"coord_index": [0, 3], "interval_borders": [0, 10], "displacements": [[[1, 0, 0]], [[0, 1, 0]]]}
    assert len(read(doc(mesh=mesh, face_def_tables=[{"fap": 3, "meshes": [good]}])).tables) == 1

    text = doc(mesh=mesh, face_def_tables=[{"fap": 3, "meshes": [dict(good, coord_index=[0, 4])]}])
    err = error(text)
    assert "coord_index 4 is beyond the mesh's 4 vertices" in err.problem
    assert (err.line, err.column) == place(text, "4", nth=text.count("4") - 1)

    text = doc(mesh=mesh, face_def_tables=[{"fap": 3, "meshes": [dict(good, interval_borders=[10, 10])]}])
    err = error(text)
    assert "strictly increasing" in err.problem

    text = doc(mesh=mesh, face_def_tables=[{"fap": 3, "meshes": [dict(good, displacements=[[[1, 0, 0]]])]}])
    assert "one entry per coord_index (2), got 1" in error(text).problem
    text = doc(mesh=mesh, face_def_tables=[{"fap": 3, "meshes": [dict(good, displacements=[[[1, 0, 0]], []])]}])
    assert "one displacement per interval (1), got 0" in error(text).problem

    text = doc(face_def_tables=[{"fap": 3, "meshes": [good]}])
    err = error(text)
    assert "needs the FDP's mesh" in err.problem
    text = doc(face_def_tables=[{"fap": 69}])
    err = error(text)
    assert "fap must lie in 1..68, got 69" in err.problem
    assert_at(err, text, "69")
    text = doc(face_def_tables=[{"fap": 5}, {"fap": 5}])
    assert "already has a table" in error(text).problem
    text = doc(face_def_tables=[{"fap": 5, "transforms": [{"field": "shear"}]}])
    err = error(text)
    assert "one of rotation, scale, translation" in err.problem
    assert_at(err, text, '"shear"')
    text = doc(face_def_tables=[{"fap": 5, "transforms": [{"field": "scale", "scale": [1, 1]}]}])
    assert "scale must have 3 numbers" in error(text).problem


def test_errors_are_never_other_exceptions_for_wrong_types_anywhere():
    shapes = [None, 1, "x", [], {}, [1], [[1, 2, 3]], {"a": 1}, True, 1.5]
    keys = ["name", "feature_points", "texture_coords", "fapu", "textures", "mesh", "face_def_tables"]
    for key in keys:
        for value in shapes:
            text = doc(**{key: value})
            try:
                read(text)
            except FdpError as err:
                assert err.line is not None and err.column is not None
