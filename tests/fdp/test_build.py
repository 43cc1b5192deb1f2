"""Building an FDP: OBJ meshes, feature points on a mesh, points files, and 3D points from two photos."""
from __future__ import annotations

import io
import json
import re

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.fdp import (MIRROR_TWINS, Fdp, FdpError, FdpMesh, FdpValueError, TextureImage, fdp_from_mesh,
                         fdp_from_photos, image_size, load_fdp, mesh_from_obj, points_from_photos, read_obj,
                         read_points_json, save_fdp, texture_from_file)
from mpeg4fa.spec import FAPS

from mpeg4fa.fdp.obj import mesh_and_groups_from_obj

from .textpos import place

# ---- OBJ ----------------------------------------------------------------------------------------

SQUARE = """# a unit square and a pentagon, with uvs
o face
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0  1.0
v 2 0 0
v 2 1 0 0.5 0.5 0.5
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vt 0.5 0
vt 0.5 1
vn 0 0 1
g skin
usemtl skin
s 1
f 1/1/1 2/2/1 3/3/1 4/4/1
f 2/2/1 5/5/1 6/6/1 3/3/1   # trailing comment
l 1 2
"""


def test_obj_quads_polygons_and_uvs():
    mesh = mesh_from_obj(SQUARE)
    assert mesh.name == "face"
    assert mesh.vertices.shape == (6, 3) and mesh.vertices[5].tolist() == [2, 1, 0]
    # trimesh splits every quad into (0, 1, 2) and (2, 3, 0), the first halves of all quads before the second
    assert mesh.triangles.tolist() == [[0, 1, 2], [1, 4, 5], [2, 3, 0], [5, 2, 1]]
    assert mesh.uvs.tolist() == [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [0.5, 1]]
    hexagon = mesh_from_obj("v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 2 0\nv -1 1 0\nf 1 2 3 4 5 6\r\n")
    assert hexagon.triangles.tolist() == [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]
    assert hexagon.uvs is None


def test_obj_negative_indices_and_corner_forms():
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvt 0 0\nf -4/1/1 -3/-1/1 -2/1\nf 2/1 4/1/1 -2/-1\n"
    mesh = mesh_from_obj(text)
    assert mesh.triangles.tolist() == [[0, 1, 2], [1, 3, 2]]
    assert mesh.uvs is None  # trimesh pairs (-2, vt 1) and (3, vt 1) as two vertices, so such uvs are not kept


def test_obj_groups_per_triangle_in_file_order():
    text = ("v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\no head\ng skin\nf 2 3 4\nf 2 3 5 4\n"
            "g teeth\nusemtl x\nf 3 5 4\ng skin\nf 2 4 5\ng eye_l\nf 1 2 3\n")
    mesh, groups = mesh_and_groups_from_obj(text)
    assert mesh == mesh_from_obj(text)
    assert groups == ["skin", "skin", "skin", "teeth", "skin", "eye_l"]  # the quad's two halves: 2nd and 3rd
    assert mesh_and_groups_from_obj(text.replace("g ", "o "))[1] == groups
    assert mesh_and_groups_from_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")[1] == [""]


@pytest.mark.parametrize("text, needle, key", [
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf 2 4 3\n", "-3", "v"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-1 2/1 3/1\nvt 1 1\n", "-1", "vt"),
])
def test_obj_relative_indices_above_more_statements_are_refused(text, needle, key):
    """trimesh counts a negative index from the file's last v/vt, so a face above more of them would shift."""
    with pytest.raises(FdpError, match=f"further '{key}' lines") as err:
        mesh_from_obj(text, "rel.obj")
    assert (err.value.line, err.value.column) == place(text, needle, 0) and err.value.hint


def test_obj_keeps_every_vertex_index_through_materials_groups_and_normals():
    """What trimesh alone would reorder or split: faces under several materials, per-corner normals, unused vertices."""
    text = ("mtllib none.mtl\nv 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvn 0 0 -1\n"
            "usemtl a\ng one\nf 2//1 3//2 4//1\nusemtl b\ng two\nf 3//1 5//1 4//2\nusemtl a\nf 2 3 5\nv 7 7 7\n")
    mesh = mesh_from_obj(text)
    assert len(mesh.vertices) == 6 and mesh.vertices[0].tolist() == [9, 9, 9] and mesh.vertices[5].tolist() == [7, 7, 7]
    assert mesh.triangles.tolist() == [[1, 2, 3], [2, 4, 3], [1, 2, 4]]


def test_obj_uvs_dropped_when_a_vertex_has_two():
    seam = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.9 0.9\nvt 0.2 0.2\n"
    assert mesh_from_obj(seam + "f 1/1 2/2 3/3\nf 2/2 4/4 3/3\n").uvs is not None
    assert mesh_from_obj(seam + "f 1/1 2/2 3/3\nf 2/2 4/4 3/5\n").uvs is None      # vertex 3: two uvs
    assert mesh_from_obj(seam + "f 1/1 2/2 3/3\nf 2 4 3\n").uvs is None            # corners without uv
    assert mesh_from_obj(seam + "v 5 5 5\nf 1/1 2/2 3/3\nf 2/2 4/4 3/3\n").uvs is None  # an unused vertex


def test_read_obj_file(tmp_path):
    path = tmp_path / "head.obj"
    path.write_text(SQUARE)
    assert read_obj(path) == mesh_from_obj(SQUARE)
    with pytest.raises(FdpError, match="no such file") as err:
        read_obj(tmp_path / "missing.obj")
    assert err.value.path.endswith("missing.obj") and err.value.hint


@pytest.mark.parametrize("text, needle, nth, problem", [
    ("v 0 0 0\nv 1 zero 0\n", "zero", 0, "'zero' is not a finite number"),
    ("v 0 0 0\nv 1 nan 0\n", "nan", 0, "not a finite number"),
    ("v 0 0 0\nv 1 0\n", "\n", 1, "a vertex needs x y z"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "4", 0, "vertex index 4 is out of range: the file has 3"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "-4", 0, "vertex index -4 points before the first vertex"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "0\n", 3, "index 0 does not exist"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "x", 0, "'x' is not an index"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/2\n", "2\n", 0, "texture coordinate index 2 is out of range"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", "1/1/1/1", 0, "more than 3 parts"),
    ("v 0 0 0\nv 1 0 0\n  f 1 2\n", "f", 0, "a face needs at least 3 corners, got 2"),
])
def test_obj_errors_at_line_and_column(text, needle, nth, problem):
    with pytest.raises(FdpError) as err:
        mesh_from_obj(text, "bad.obj")
    assert problem in err.value.problem and err.value.hint
    line, col = place(text, needle, nth)
    assert (err.value.path, err.value.line, err.value.column) == ("bad.obj", line, col), str(err.value)


def test_obj_without_faces():
    with pytest.raises(FdpError, match="no faces") as err:
        mesh_from_obj("v 0 0 0\nv 1 0 0\n", "points.obj")
    assert err.value.path == "points.obj" and err.value.hint


# ---- fdp_from_mesh ------------------------------------------------------------------------------


def test_fdp_from_mesh_vertex_points_get_uvs():
    mesh = mesh_from_obj(SQUARE)
    fdp = fdp_from_mesh(mesh, {"9.3": 2, "2.1": np.int64(1)}, name="me", fapu={"ES0": 2.0})
    assert fdp.mesh == mesh and fdp.name == "me" and fdp.fapu == {"ES0": 2.0}
    assert fdp.labels == ("2.1", "9.3")
    assert fdp.points.tolist() == [[1, 0, 0], [1, 1, 0]]
    assert fdp.texture_coords.tolist() == [[1, 0], [1, 1]]


def test_fdp_from_mesh_explicit_points_drop_texture_coords():
    mesh = mesh_from_obj(SQUARE)
    fdp = fdp_from_mesh(mesh, {"9.3": 2, "2.1": [0.5, -0.5, 0.25]})
    assert fdp.point("2.1").tolist() == [0.5, -0.5, 0.25] and fdp.point("9.3").tolist() == [1, 1, 0]
    assert fdp.texture_coords is None
    no_uvs = FdpMesh(mesh.vertices, mesh.triangles)
    assert fdp_from_mesh(no_uvs, {"9.3": 2}).texture_coords is None


@pytest.mark.parametrize("points, message, where", [
    ({"9.3": 6}, "9.3 is vertex 6, but the mesh has 6 vertices", ("feature_points", "9.3")),
    ({"9.3": -1}, "9.3 is vertex -1", ("feature_points", "9.3")),
    ({"9.3": [1, 2]}, "feature point 9.3 must be a vertex index or [x, y, z]", ("feature_points", "9.3")),
    ({"9.3": True}, "feature point 9.3 must be", ("feature_points", "9.3")),
    ({"12.1": 0}, "unknown feature point label '12.1'", ("feature_points", "12.1")),
])
def test_fdp_from_mesh_errors_name_the_label(points, message, where):
    with pytest.raises(FdpValueError, match=re.escape(message)) as err:
        fdp_from_mesh(mesh_from_obj(SQUARE), points)
    assert err.value.field == where


# ---- points files -------------------------------------------------------------------------------


def test_read_points_json(tmp_path):
    photo = tmp_path / "front.json"
    photo.write_text('{"3.5": [410.5, 220], "9.3": [400, 300]}')
    assert read_points_json(photo) == {"3.5": (410.5, 220.0), "9.3": (400.0, 300.0)}
    mesh = tmp_path / "mesh.json"
    mesh.write_text('{"3.5": 17, "9.3": [0, 1.5, 2]}')
    assert read_points_json(mesh) == {"3.5": 17, "9.3": (0.0, 1.5, 2.0)}


@pytest.mark.parametrize("text, needle, problem", [
    ('{"3.5": [1, 2],\n "9.3": [1, 2}', "}", "invalid JSON"),
    ('{"3.5": [1, 2],\n "9.3": [1, 2, 3, 4]}', "[1, 2, 3, 4]", "point 9.3 must be [x, y], [x, y, z] or a vertex index"),
    ('{"3.5": [1, 2],\n "9.3": "nose"}', '"nose"', "point 9.3 must be"),
    ('{"3.5": [1, 2],\n "9.3": [1, true]}', "true", "coordinate of point 9.3 must be a number"),
    ('{"3.5": [1, 2],\n "9.3": -4}', "-4", "vertex index of 9.3 must lie in"),
    ('{"3.5": [1, 2],\n "13.3": [1, 2]}', '"13.3"', "unknown feature point label '13.3'"),
    ('{"3.5": [1, 2],\n "3.5": [1, 2]}', '"3.5"', "given twice"),
    ('{"3.5": [1, 2],\n "9.3": [1, 2, 3]}', "[1, 2, 3]", "point 9.3 is a mesh point"),
    ('[[1, 2]]', "[", "must be a JSON object"),
])
def test_read_points_json_errors(tmp_path, text, needle, problem):
    path = tmp_path / "points.json"
    path.write_text(text)
    with pytest.raises(FdpError, match=re.escape(problem)) as err:
        read_points_json(path)
    nth = 1 if needle == '"3.5"' else 0
    assert (err.value.line, err.value.column) == place(text, needle, nth), str(err.value)
    assert err.value.path == str(path)


# ---- photos -------------------------------------------------------------------------------------

HALF_FACE = {  # mm, +x the face's left, +y up, +z out of the face; right-side twins are mirrored below
    "11.1": (0, 75, 80), "11.3": (45, 65, 60), "11.4": (0, 110, 0), "11.6": (0, 20, -95),
    "3.1": (32, 35, 80), "3.3": (32, 25, 79), "3.5": (32, 30, 78), "3.7": (45, 30, 70), "3.11": (18, 30, 75),
    "4.1": (15, 45, 85), "4.3": (32, 50, 84), "4.5": (50, 45, 72),
    "9.3": (0, 0, 105), "9.15": (0, -12, 95), "9.12": (0, 20, 95), "9.1": (15, -5, 88),
    "8.1": (0, -25, 92), "8.2": (0, -40, 90), "8.3": (25, -32, 80), "8.5": (12, -27, 89), "8.7": (12, -38, 87),
    "2.1": (0, -70, 80), "2.10": (0, -60, 88), "2.2": (0, -31, 90), "2.3": (0, -33, 89),
    "2.4": (22, -32, 82), "2.6": (10, -30, 88), "2.8": (10, -34, 87), "2.13": (55, -35, 20),
    "5.1": (45, -10, 70), "10.1": (70, 35, -5), "10.3": (75, 20, -20), "10.5": (72, -10, 0), "10.9": (68, 25, 5),
}
FACE = {**HALF_FACE, **{MIRROR_TWINS[k]: (-x, y, z) for k, (x, y, z) in HALF_FACE.items() if k in MIRROR_TWINS}}
FRONT_SCALE, FRONT_CENTRE = 3.0, (400.0, 350.0)


def front_photo(points: dict) -> dict[str, tuple[float, float]]:
    cx, cy = FRONT_CENTRE
    return {k: (cx + FRONT_SCALE * x, cy - FRONT_SCALE * y) for k, (x, y, _) in points.items()}


def side_photo(points: dict, view: str, scale: float = 2.2, centre=(250.0, 330.0)) -> dict[str, tuple[float, float]]:
    """Orthographic side view: a 'left' photo has the head's -z to the image's right, a 'right' photo +z."""
    sign = -1.0 if view == "left" else 1.0
    return {k: (centre[0] + scale * sign * z, centre[1] - scale * y) for k, (_, y, z) in points.items()}


def similarity_error(original: dict, rebuilt: dict) -> tuple[float, float]:
    """(scale, max residual / extent) of the best fit rebuilt ~ scale * original + shift."""
    labels = sorted(original)
    a = np.array([original[k] for k in labels], float)
    b = np.array([rebuilt[k] for k in labels], float)
    a0, b0 = a - a.mean(axis=0), b - b.mean(axis=0)
    scale = float(np.sum(a0 * b0) / np.sum(a0 * a0))
    return scale, float(np.abs(b0 - scale * a0).max() / np.ptp(b, axis=0).max())


@pytest.mark.parametrize("view", ["left", "right"])
def test_photos_round_trip_up_to_scale_and_shift(view):
    rng = np.random.default_rng(3)
    face = {k: np.array(p, float) + rng.normal(scale=2.0, size=3) for k, p in FACE.items()}  # not symmetric
    rebuilt = points_from_photos(front_photo(face), side_photo(face, view), side_view=view)
    assert set(rebuilt) == set(face) and all(p.shape == (3,) for p in rebuilt.values())
    scale, error = similarity_error(face, rebuilt)
    assert scale == pytest.approx(FRONT_SCALE, rel=1e-9) and error < 1e-6
    xy = np.array([p[:2] for p in rebuilt.values()])
    assert np.allclose(xy.min(axis=0) + xy.max(axis=0), 0)          # x, y origin: centre of the front box
    z = np.array([p[2] for p in rebuilt.values()])
    assert z.min() + z.max() == pytest.approx(0, abs=1e-9)         # z origin: centre of the side box


def test_photos_input_orders_and_side_only_points():
    face = {k: np.array(p, float) for k, p in FACE.items()}
    front = front_photo({k: p for k, p in face.items() if k != "11.6"})      # back of skull: side photo only
    rebuilt = points_from_photos(front, side_photo(face, "left"), side_view="left")
    assert list(rebuilt) == sorted(rebuilt, key=lambda k: [int(n) for n in k.split(".")])
    assert "11.6" not in rebuilt and len(rebuilt) == len(face) - 1


@pytest.mark.parametrize("view", ["left", "right"])
def test_hidden_half_takes_the_twins_depth(view):
    face = {k: np.array(p, float) for k, p in FACE.items()}
    seen = {k: p for k, p in face.items() if (p[0] >= 0) == (view == "left") or p[0] == 0}
    rebuilt = points_from_photos(front_photo(face), side_photo(seen, view), side_view=view)
    assert set(rebuilt) == set(face)                                  # the face is symmetric: all exact
    assert similarity_error(face, rebuilt)[1] < 1e-6
    # a front-only point whose twin is not on the side photo is left out, not guessed
    no_twin = {k: p for k, p in seen.items() if k not in ("3.5", "3.6")}
    rebuilt = points_from_photos(front_photo(face), side_photo(no_twin, view), side_view=view)
    assert "3.5" not in rebuilt and "3.6" not in rebuilt and "3.7" in rebuilt and "3.12" in rebuilt


def test_mirror_twins_follow_the_spec_tables():
    pairs = {frozenset(p) for p in MIRROR_TWINS.items()}
    assert len(pairs) == 32 and all(MIRROR_TWINS[b] == a for a, b in MIRROR_TWINS.items())
    for a, b in [("3.5", "3.6"), ("2.4", "2.5"), ("3.7", "3.12"), ("3.8", "3.11"), ("4.1", "4.2"), ("2.6", "2.7"),
                 ("8.5", "8.6"), ("8.9", "8.10"), ("9.4", "9.5"), ("10.9", "10.10"), ("11.2", "11.3")]:
        assert MIRROR_TWINS[a] == b
    for label in ("2.1", "9.3", "11.4", "11.5", "7.1", "6.1", "8.1", "2.2"):
        assert label not in MIRROR_TWINS
    # independent check: FAPs named ..._l_... / ..._r_... (or _lm / _rm) move twin points
    by_name = {f.name: f for f in FAPS}
    checked = 0
    for fap in FAPS:
        for left, right in (("_l_", "_r_"), ("_lm", "_rm")):
            other = by_name.get(fap.name.replace(left, right))
            if left in fap.name and other is not None:
                assert MIRROR_TWINS[fap.feature_point[0]] == other.feature_point[0], fap.name
                checked += 1
    assert checked >= 20


def test_photos_wrong_way_errors():
    face = {k: np.array(p, float) for k, p in FACE.items()}
    front, left = front_photo(face), side_photo(face, "left")
    mirrored = {k: (800 - x, y) for k, (x, y) in front.items()}
    with pytest.raises(FdpValueError, match="wrong way across the image.*face's left side should be on the image's"):
        points_from_photos(mirrored, left, side_view="left")
    swapped = dict(front, **{"3.5": front["3.6"], "3.6": front["3.5"]})
    with pytest.raises(FdpValueError, match="3.5 .face's left. is left of 3.6") as err:
        points_from_photos(swapped, left, side_view="left")
    assert err.value.field == ("front", "3.5")
    with pytest.raises(FdpValueError, match="in a 'right' photo the nose should point to the image's right"):
        points_from_photos(front, left, side_view="right")
    upside_down = {k: (x, 600 - y) for k, (x, y) in left.items()}
    with pytest.raises(FdpValueError, match="left photo points run the wrong way up"):
        points_from_photos(front, upside_down, side_view="left")


def test_photos_too_little_shared():
    face = {k: np.array(p, float) for k, p in FACE.items()}
    front = front_photo(face)
    no_back = {k: p for k, p in front.items() if k != "11.6"}
    with pytest.raises(FdpValueError, match="1 label.s. annotated on both photos"):
        points_from_photos(no_back, side_photo({"9.3": face["9.3"], "11.6": face["11.6"]}, "left"), side_view="left")
    flat = side_photo({k: face[k] for k in ("3.5", "3.7")}, "left")   # pupil and eye corner: same height
    with pytest.raises(FdpValueError, match=r"\(3.5, 3.7\) span only 0 px vertically on the front photo"):
        points_from_photos(front, flat, side_view="left")


@pytest.mark.parametrize("front, side, view, message, where", [
    ({"3.5": (1, 2), "99": (1, 2)}, {}, "left", "unknown feature point label '99'", ("front", "99")),
    ({"3.5": (1, np.inf)}, {}, "left", "front photo point 3.5 must be (x, y) pixels", ("front", "3.5")),
    ({}, {"3.5": (1, 2, 3)}, "right", "right photo point 3.5 must be (x, y)", ("right", "3.5")),
    ({}, {}, "top", "side_view must be 'left' or 'right'", ("side_view",)),
])
def test_photos_bad_input(front, side, view, message, where):
    with pytest.raises(FdpValueError, match=re.escape(message)) as err:
        points_from_photos(front, side, side_view=view)
    assert err.value.field == where


# ---- fdp_from_photos and textures ---------------------------------------------------------------


def image_bytes(fmt: str, size=(800, 600)) -> bytes:
    out = io.BytesIO()
    Image.new("RGB", size, (200, 150, 120)).save(out, fmt)
    return out.getvalue()


@pytest.mark.parametrize("fmt, media_type", [("PNG", "image/png"), ("JPEG", "image/jpeg")])
def test_texture_from_file(tmp_path, fmt, media_type):
    path = tmp_path / f"front.{fmt.lower()}"
    path.write_bytes(image_bytes(fmt, (64, 48)))
    texture = texture_from_file(path)
    assert (texture.name, texture.media_type, texture.data) == (path.name, media_type, path.read_bytes())
    assert image_size(texture.data) == (64, 48)


def test_texture_from_file_errors(tmp_path):
    path = tmp_path / "front.gif"
    path.write_bytes(b"GIF89a....")
    with pytest.raises(FdpError, match="not a PNG or JPEG") as err:
        texture_from_file(path)
    assert err.value.offset == 0 and "convert" in err.value.hint
    with pytest.raises(FdpError, match="no such file"):
        texture_from_file(tmp_path / "none.png")
    assert image_size(b"GIF89a") is None and image_size(image_bytes("PNG")[:20]) is None
    assert image_size(image_bytes("JPEG")[:30]) is None


def test_fdp_from_photos_texture_coords_and_file_round_trip(tmp_path):
    face = {k: np.array(p, float) for k, p in FACE.items()}
    front, side = front_photo(face), side_photo(face, "right")
    texture = TextureImage("front.png", "image/png", image_bytes("PNG"))
    fdp = fdp_from_photos(front, side, side_view="right", texture=texture, name="alice")
    assert fdp.textures == (texture,) and fdp.name == "alice" and fdp.mesh is None
    expected = np.array([[front[k][0] / 800, 1 - front[k][1] / 600] for k in fdp.labels])
    assert np.array_equal(fdp.texture_coords, expected)
    assert fdp.as_dict().keys() == points_from_photos(front, side, side_view="right").keys()
    assert fdp_from_photos(front, side, side_view="right", front_size=(800, 600), texture=texture, name="alice") == fdp
    no_texture = fdp_from_photos(front, side, side_view="right", front_size=(800, 600))
    assert no_texture.textures == () and np.array_equal(no_texture.texture_coords, expected)
    assert fdp_from_photos(front, side, side_view="right").texture_coords is None
    for name in ("alice.fdp", "alice.json"):
        save_fdp(fdp, tmp_path / name)
        again = load_fdp(tmp_path / name)
        assert again == fdp and again.textures[0].data == texture.data


def test_fdp_from_photos_size_errors():
    face = {k: np.array(p, float) for k, p in FACE.items()}
    front, side = front_photo(face), side_photo(face, "left")
    png = TextureImage("front.png", "image/png", image_bytes("PNG"))
    with pytest.raises(FdpValueError, match=r"front_size \(640, 480\) differs from the texture's own size"):
        fdp_from_photos(front, side, front_size=(640, 480), texture=png)
    with pytest.raises(FdpValueError, match="lies outside the 300x600 photo"):
        fdp_from_photos(front, side, front_size=(300, 600))
    with pytest.raises(FdpValueError, match="front_size must be"):
        fdp_from_photos(front, side, front_size=(800.0, 600))
    opaque = TextureImage("front.webp", "image/webp", b"RIFF....WEBP")
    with pytest.raises(FdpValueError, match="cannot read the size of texture 'front.webp'"):
        fdp_from_photos(front, side, texture=opaque)
    fdp = fdp_from_photos(front, side, front_size=(800, 600), texture=opaque)
    assert fdp.textures == (opaque,)


def test_points_file_to_fdp(tmp_path):
    face = {k: np.array(p, float) for k, p in FACE.items()}
    for view, points in (("front", front_photo(face)), ("left", side_photo(face, "left"))):
        (tmp_path / f"{view}.json").write_text(json.dumps(points))
    fdp = fdp_from_photos(read_points_json(tmp_path / "front.json"), read_points_json(tmp_path / "left.json"))
    assert isinstance(fdp, Fdp) and similarity_error(face, fdp.as_dict())[1] < 1e-6
